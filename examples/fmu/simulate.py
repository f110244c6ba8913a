#!/usr/bin/env python3
"""Simulates the absorber FMU with FMPy (docs/fmu.md): the paper's arm shaken at its base,
once with the paper's track radius and once with the tuned one (`host-sim tune`), as a
controller engineer would drive it: the base acceleration is an input signal, a parameter is
changed through its start value, the outputs come back as arrays.

    cargo run --release -p host-sim -- fmu --scene paper --fmi-version 3 --out absorber.fmu
    python examples/fmu/simulate.py absorber.fmu

Needs `pip install fmpy` (and matplotlib for --plot).
"""

import argparse
import math

import numpy as np
from fmpy import read_model_description, simulate_fmu


def base_acceleration(t, amplitude=0.5e-3, frequency=4.13):
    """The paper's excitation y_b = A sin(2 pi f t), as an acceleration [m/s^2]."""
    w = 2.0 * math.pi * frequency
    return -amplitude * w * w * np.sin(w * t)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu", help="an FMU made by `host-sim fmu` (FMI 3.0 or 2.0)")
    p.add_argument("--duration", type=float, default=60.0, help="simulated time [s]")
    p.add_argument("--plot", help="write the tip deflection of both runs to this PNG (needs matplotlib)")
    a = p.parse_args()

    md = read_model_description(a.fmu)
    h = float(md.defaultExperiment.stepSize)  # the model's fixed step: communicate every k h
    t = np.arange(int(round(a.duration / h)) + 1) * h
    # The FMU holds an input over a communication step and applies it at the step's end: the
    # value given at t is the sample of t + h.
    signal = np.zeros(len(t), dtype=[("time", np.float64), ("base_acceleration", np.float64), ("tip_load", np.float64)])
    signal["time"] = t
    signal["base_acceleration"] = base_acceleration(t + h)
    outputs = ["tip_deflection", "tip_acceleration", "root_stress", "ball_relative_angle", "contact", "damage"]

    runs = {}
    for label, start in [("paper R = 39.5 mm", {}), ("tuned R = 48.8 mm", {"ball.track_radius": 0.048819008})]:
        r = simulate_fmu(a.fmu, stop_time=t[-1], output_interval=h, input=signal, output=outputs, start_values=start)
        runs[label] = r
        steady = r["time"] >= 20.0
        y = r["tip_deflection"][steady]
        s = r["root_stress"][steady]
        print(
            f"{label}: tip amplitude (t >= 20 s, half peak-to-peak) {1e3 * (y.max() - y.min()) / 2:.3f} mm, "
            f"root stress range {1e-6 * (s.max() - s.min()):.2f} MPa, "
            f"ball max |theta - psi| {math.degrees(np.abs(r['ball_relative_angle']).max()):.1f} deg, "
            f"in flight {100 * np.mean(r['contact'] == 2):.1f} % of the time, "
            f"Miner damage {r['damage'][-1]:.3e} in {t[-1]:g} s"
        )

    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(9, 4))
        for label, r in runs.items():
            ax.plot(r["time"], 1e3 * r["tip_deflection"], lw=0.6, label=label)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("tip deflection [mm]")
        ax.legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=120)
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
