"""The stack's settling metrics from a run's probes.csv columns and summary.json, shared by
test_contact_stack.py and ci/gpu/stack_run.py (the long GPU run). numpy only."""
import numpy as np

D_DEM = 0.01


def stack_metrics(p, summary, t_window):
    """p: probes.csv as {column: array}; summary: summary.json as a dict; t_window: the final
    stretch [s] over which lateral drift is measured."""
    t, ke = p["time"], p["kinetic"]
    names = sorted({k[:-2] for k in p if k.endswith("_x") and k.startswith("c")})
    late = t >= t[-1] - t_window
    c = summary.get("contact", {})
    return {
        # kinetic energy at the end over its peak: the stack lands, then settles
        "ke_end_over_peak": float(ke[-1] / ke.max()),
        # peak-to-peak x, y of every cube centre over the last t_window [m]
        "lateral_drift": max(float(np.ptp(p[f"{n}_{a}"][late])) for n in names for a in "xy"),
        # largest D_DEM - gap over the run [m]; 2 D_DEM means the surfaces themselves meet
        "max_overlap": float(c.get("max_overlap_ever", np.nan)),
        # largest vertical movement of a cube centre [m]
        "vertical_settlement": max(float(abs(p[f"{n}_z"][-1] - p[f"{n}_z"][0])) for n in names),
    }
