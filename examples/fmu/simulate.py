#!/usr/bin/env python3
"""Simulates the absorber FMU with FMPy (docs/fmu.md): the paper's arm shaken at its base,
once with the paper's track radius and once with the tuned one (`host-sim tune`), as a
controller engineer would drive it: the base acceleration is an input signal, a parameter is
changed through its start value, the outputs come back as arrays.

The free ball's run is chaotic: a change in the last bit of one input sample, or of the ball's
initial angle, leads to another trajectory and another steady amplitude. So each figure is
printed beside an ensemble: the same run from `--ensemble` initial ball angles spread
uniformly over +-0.1 deg about the scene's (seeded, `--seed`), as mean +- sd (min-max). With
`--ensemble` > 1 the paper radius also runs on the input sampled as `host-sim` samples it
(sin(w k h) in double precision, not numpy's sin(w (t + h))): how many samples differ and by
how much, and the figure the FMU then gives (host-sim's own, to the last digit).

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
    p.add_argument("--ensemble", type=int, default=8, help="runs per radius for the spread (1: none)")
    p.add_argument("--seed", type=int, default=1, help="seed of the initial angle perturbations")
    p.add_argument("--plot", help="write the tip deflection of both runs to this PNG (needs matplotlib)")
    a = p.parse_args()
    if a.ensemble < 1:
        p.error("--ensemble must be at least 1")

    md = read_model_description(a.fmu)
    h = float(md.defaultExperiment.stepSize)  # the model's fixed step: communicate every k h
    t = np.arange(int(round(a.duration / h)) + 1) * h
    # The FMU holds an input over a communication step and applies it at the step's end: the
    # value given at t is the sample of t + h.
    signal = np.zeros(len(t), dtype=[("time", np.float64), ("base_acceleration", np.float64), ("tip_load", np.float64)])
    signal["time"] = t
    signal["base_acceleration"] = base_acceleration(t + h)
    outputs = ["tip_deflection", "tip_acceleration", "root_stress", "ball_relative_angle", "contact", "damage"]

    angle0 = next(v.start for v in md.modelVariables if v.name == "ball.initial_angle")
    angle0 = float(angle0)
    rng = np.random.default_rng(a.seed)
    deltas = [0.0] + list(np.radians(rng.uniform(-0.1, 0.1, a.ensemble - 1)))

    def amplitude(r):
        """The steady tip amplitude [mm]: half peak-to-peak over t >= 20 s (as `host-sim paper`)."""
        y = r["tip_deflection"][r["time"] >= 20.0]
        return 1e3 * (y.max() - y.min()) / 2

    runs = {}
    for label, start in [("paper R = 39.5 mm", {}), ("tuned R = 48.8 mm", {"ball.track_radius": 0.048819008})]:
        r = simulate_fmu(a.fmu, stop_time=t[-1], output_interval=h, input=signal, output=outputs, start_values=start)
        runs[label] = r
        steady = r["time"] >= 20.0
        s = r["root_stress"][steady]
        print(
            f"{label}: tip amplitude (t >= 20 s, half peak-to-peak) {amplitude(r):.3f} mm, "
            f"root stress range {1e-6 * (s.max() - s.min()):.2f} MPa, "
            f"ball max |theta - psi| {math.degrees(np.abs(r['ball_relative_angle']).max()):.1f} deg, "
            f"in flight {100 * np.mean(r['contact'] == 2):.1f} % of the time, "
            f"Miner damage {r['damage'][-1]:.3e} in {t[-1]:g} s"
        )
        if a.ensemble > 1 and not start:
            # The input as host-sim gives it (scripts/fmu-check.py): initialization sees sample
            # 0 (the table has an event at t = 0: before it sample 0, after it sample 1), and
            # sample k is -A w^2 sin(w k h) in double precision.
            w = 2.0 * math.pi * 4.13
            n = len(t) - 1
            exact = np.array([-0.5e-3 * w * w * math.sin(w * k * h) for k in range(n + 1)])
            differ = np.abs(exact[1:] - signal["base_acceleration"][:n])
            for what, samples in [("numpy's samples", signal["base_acceleration"][:n]), ("host-sim's samples", exact[1:])]:
                u = np.zeros(n + 2, dtype=signal.dtype)
                u["time"][0] = -h
                u["time"][2:] = np.arange(n) * h
                u["base_acceleration"][:2] = exact[0]
                u["base_acceleration"][2:] = samples
                e = simulate_fmu(a.fmu, stop_time=n * h, output_interval=h, input=u, output=["tip_deflection"])
                print(f"{label}: started as host-sim starts (input 0 at initialization), {what}: tip amplitude {amplitude(e):.3f} mm")
            print(
                f"{label}: numpy's and host-sim's samples differ in {(differ > 0).sum()} of {n} by at most "
                f"{differ.max():.1e} m/s^2; the example's own start sees sample 1 ({signal['base_acceleration'][0]:.4f} m/s^2)"
            )
        if a.ensemble > 1:
            y = [amplitude(r)]
            for d in deltas[1:]:
                m = simulate_fmu(
                    a.fmu, stop_time=t[-1], output_interval=h, input=signal, output=["tip_deflection"],
                    start_values={**start, "ball.initial_angle": angle0 + d},
                )
                y.append(amplitude(m))
            y = np.array(y)
            print(
                f"{label}: tip amplitude over {a.ensemble} runs from initial ball angles within +-0.1 deg "
                f"(seed {a.seed}): {y.mean():.2f} +- {y.std(ddof=1):.2f} mm ({y.min():.2f}-{y.max():.2f})"
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
