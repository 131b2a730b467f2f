#!/usr/bin/python3
"""Spread of the headline numbers between time-step / stiffness settings.

Reads the provenance JSONs written by run_all.sh and writes results/convergence.json:
for each case, the value of each headline number under each setting, the spread
(max - min) and the spread relative to the base setting. The spread bounds what a
comparison of qdemsph with these references can claim: differences smaller than it are
not resolved by the reference.

Run with /usr/bin/python3 (no YADE needed): /usr/bin/python3 convergence.py [results]
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

# case -> (file stems: base first, headline result keys)
CASES = {
    "sliding_mu0.5_v3": (["sliding", "sliding_halfdt", "sliding_stiff4"],
                         ["stop_distance_m", "stop_time_s"]),
    "shogi_two_mu0.1": (["shogi_two_mu0.1", "shogi_two_mu0.1_halfdt", "shogi_two_mu0.1_stiff4"],
                        ["struck_t_tilt_1_s", "struck_t_tilt_45_s", "falling_t_tilt_45_s",
                         "falling_t_tilt_80_s"]),
    "shogi_two_mu0.5": (["shogi_two_mu0.5", "shogi_two_mu0.5_halfdt", "shogi_two_mu0.5_stiff4"],
                        ["struck_t_tilt_1_s", "struck_t_tilt_45_s", "struck_t_tilt_80_s",
                         "falling_t_tilt_45_s"]),
    "shogi_two_pitch30mm_mu0.1": (["shogi_two_mu0.1_pitch30mm", "shogi_two_mu0.1_pitch30mm_stiff4"],
                                  ["struck_t_tilt_1_s", "struck_t_tilt_45_s", "falling_t_tilt_45_s"]),
    "shogi_two_pitch30mm_mu0.5": (["shogi_two_mu0.5_pitch30mm", "shogi_two_mu0.5_pitch30mm_stiff4"],
                                  ["struck_t_tilt_1_s", "struck_t_tilt_45_s", "struck_t_tilt_80_s",
                                   "falling_t_tilt_45_s"]),
    # The chain variants are 20 pieces long (cost); every run's front speed is refitted over
    # the window the runs share, pieces 5..18 (derived from the stored fall times).
    "shogi_chain": (["shogi_chain_n40", "shogi_chain_n20_stiff4", "shogi_chain_n20_dt2x",
                     "shogi_chain_n20_stiff16"],
                    ["front_speed_pieces_5_18_m_per_s"]),
    "shogi_one_onto_two_mu0.1": (["shogi_one_onto_two_mu0.1", "shogi_one_onto_two_mu0.1_stiff4"],
                                 ["striker_t_tilt_45_s", "striker_t_tilt_80_s"]),
    "shogi_one_onto_two_mu0.5": (["shogi_one_onto_two_mu0.5", "shogi_one_onto_two_mu0.5_stiff4"],
                                 ["striker_t_tilt_45_s"]),
}
WINDOW = (5, 18)


def derived(rec, key):
    """Headline numbers not stored as such: the chain front speed over WINDOW."""
    if key == "front_speed_pieces_5_18_m_per_s":
        fall, pitch = rec["results"]["fall_time_s"], rec["params"]["pitch_m"]
        idx = [i for i in range(WINDOW[0], WINDOW[1] + 1) if i < len(fall) and fall[i] is not None]
        if len(idx) < WINDOW[1] - WINDOW[0] + 1:
            return None
        return common.linear_fit([fall[i] for i in idx], [i * pitch for i in idx])[0]
    return rec["results"].get(key)


def main(folder):
    out = {"what": "spread of headline numbers between dt / contact-stiffness settings "
                   "(base = first setting)", "cases": {}}
    for case, (stems, keys) in CASES.items():
        settings, missing = [], []
        for stem in stems:
            path = os.path.join(folder, stem + ".provenance.json")
            if not os.path.exists(path):
                missing.append(stem)
                continue
            with open(path) as f:
                rec = json.load(f)
            settings.append({"name": stem, "dt": rec["params"]["dt"],
                             "young": rec["params"]["young"],
                             "values": {k: derived(rec, k) for k in keys}})
        entry = {"settings": settings, "missing": missing, "spread": {}}
        for k in keys:
            vals = [s["values"][k] for s in settings if s["values"][k] is not None]
            if len(vals) < 2 or settings[0]["values"][k] is None:
                entry["spread"][k] = None
                continue
            base = settings[0]["values"][k]
            d = max(vals) - min(vals)
            entry["spread"][k] = {
                "base": base, "abs": d, "rel": d / abs(base),
                "minus_base": {s["name"]: (s["values"][k] - base if s["values"][k] is not None else None)
                               for s in settings[1:]}}
        out["cases"][case] = entry
    path = os.path.join(folder, "convergence.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=2)
        f.write("\n")
    for case, e in out["cases"].items():
        for k, s in e["spread"].items():
            print("%-18s %-22s %s" % (case, k, "n/a" if s is None else
                                       "base %.6g  spread %.3g (%.2g %%)" % (s["base"], s["abs"], 100 * s["rel"])))
    return out


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "results"))
