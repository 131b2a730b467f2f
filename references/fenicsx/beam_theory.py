"""Closed-form tip deflection of an end-loaded cantilever (BENCHMARKS.md section 1)."""


def beam_theory(E, nu, L, B, H, P):
    """(Euler-Bernoulli, Timoshenko) tip deflection magnitudes for end load P.

    d_EB = P L^3 / (3 E I), I = B H^3 / 12;  d_T = d_EB + P L / (k G A),
    G = E / (2 (1 + nu)), A = B H, Cowper's k = 10 (1 + nu) / (12 + 11 nu)."""
    inertia = B * H**3 / 12.0
    d_eb = P * L**3 / (3.0 * E * inertia)
    G = E / (2.0 * (1.0 + nu))
    k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
    return d_eb, d_eb + P * L / (k * G * B * H)
