#!/usr/bin/env python3
"""Shrinks a pyrocam model file into a small fuzzing seed that still loads: the wavelength grid
thinned to every 10th sample (curves and QE matrices alike), the network cut to one hidden layer
of 4 units, the uncertainty table thinned alike, numbers rounded, the summary dropped.
Usage: shrink-model.py MODEL.json OUT.json (the checksum is left stale: fuzz_model sets it before
each load)."""
import json
import sys

KEEP = 10  # set from the grid: about 16 samples are kept


def thin(o, n):
    if isinstance(o, list) and len(o) == n:
        return [thin(v, n) for v in o[::KEEP]]
    if isinstance(o, list):
        return [thin(v, n) for v in o]
    if isinstance(o, dict):
        return {k: thin(v, n) for k, v in o.items()}
    if isinstance(o, float):
        return float("%.4g" % o)
    return o


def main():
    f = json.load(open(sys.argv[1]))
    p = f["payload"]
    g = p["profile"]["wavelength_grid_nm"]
    n = round((g["stop"] - g["start"]) / g["step"]) + 1
    global KEEP
    KEEP = next(k for k in range(1, n) if (n - 1) % k == 0 and (n - 1) // k <= 15)
    g["step"] *= KEEP
    mlp = p.pop("mlp")
    p = thin(p, n)
    u = p["uncertainty"]
    for k in ("temperature_c", "u_calibration_c", "u_emissivity_c"):
        u[k] = u[k][::KEEP] + ([u[k][-1]] if (len(u[k]) - 1) % KEEP else [])
    inputs = len(mlp["layers"][0]["weights"][0])
    mlp["layers"] = [
        {"weights": [[0.5 * (i - j) for j in range(inputs)] for i in range(4)], "bias": [0.1] * 4},
        {"weights": [[0.25, -0.5, 0.75, 1.0]], "bias": [0.0]},
    ]
    p["mlp"] = thin(mlp, -1)
    p["summary"] = {}
    f["payload"] = p
    json.dump(f, open(sys.argv[2], "w"), separators=(",", ":"))


main()
