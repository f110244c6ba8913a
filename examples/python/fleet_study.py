#!/usr/bin/env python3
"""Wind fatigue of a traffic-signal mast arm, at fleet scale on Dask: N ten-minute wind records
sampled from a climate, each run as an independent task, the damage per year with a
confidence interval, with and without a ball absorber at the arm's end.

    python examples/python/fleet_study.py --records 256               # a LocalCluster here
    python examples/python/fleet_study.py --records 100000 --scheduler tcp://head:8786
    python examples/python/fleet_study.py --records 64 --serial       # no Dask (the baseline)

The arm is scenes/mast-arm.toml (16.8 m tapered tube, three signal heads, f1 = 1.03 Hz) with
its wind model (docs/monitoring.md): vertical Kaimal turbulence (buffeting), vortex shedding
from the heads at lock-in, truck gusts. Each record draws its climate (assumptions, stated
here and in docs/fleet.md): the mean wind speed from a Weibull distribution (shape 2, scale
5 m/s at the arm's height: mean 4.4 m/s), the turbulence intensity lognormal about 0.2,
vortex shedding in one to three episodes when the mean speed lies within ±15 % of the
lock-in speed St·U/D = f1 and the turbulence intensity is at most 0.15 (lock-in needs a steady
flow), trucks as a Poisson stream of 30 per hour, and its own turbulence
realization (the seed). The absorber: a 10 kg steel ball in a circular track tuned to half the
arm's first frequency, in a 15 kg housing at the arm's end (`host-sim tune` says such a track,
about 1.35 m wide, does not fit in a signal head: this study says what it would buy).

Progress: Dask's progress bar (and the dashboard's address). `docs/fleet.md` says how to run
it on SLURM or PBS with dask-jobqueue.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore

import numpy as np

from absorber import fleet

SCENE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes", "mast-arm.toml")

#: Climate of the arm's site (assumptions; docs/fleet.md).
WEIBULL_SHAPE = 2.0
WEIBULL_SCALE = 5.0  # [m/s] at the arm's height
TURBULENCE_MEDIAN = 0.2
TURBULENCE_LOG_SD = 0.25
LOCK_IN_BAND = 0.15
LOCK_IN_TURBULENCE = 0.15  # vortices lock in only in a steady, low-turbulence flow
TRUCKS_PER_HOUR = 30.0
#: The absorber (assumptions).
BALL_MASS = 10.0  # [kg], steel
HOUSING_MASS = 15.0  # [kg]
STEEL = 7850.0  # [kg/m^3]


def base_scene(path: str = SCENE) -> dict:
    """The mast-arm scene as a dict, without its sensor (no estimator here)."""
    with open(path, "rb") as f:
        s = tomllib.load(f)
    s.pop("sensor", None)
    return s


def with_absorber(scene: dict) -> dict:
    """`scene` with the absorber's housing (`[tip]`) and ball (`[ball]`), the track radius
    tuned so that the ball's frequency on a fixed track is half the arm's first frequency with
    the ball locked: rho = g / ((1 + J/(m r^2)) (pi f1)^2) (solid ball: J = 2/5 m r^2)."""
    r = (3.0 * BALL_MASS / (4.0 * math.pi * STEEL)) ** (1.0 / 3.0)
    s = json.loads(json.dumps(scene))
    s["tip"] = {"mass": HOUSING_MASS, "inertia": HOUSING_MASS * 0.3**2, "offset": 0.3}
    s["ball"] = {
        "mass": BALL_MASS,
        "inertia": 0.4 * BALL_MASS * r * r,
        "radius": r,
        "track_radius": 0.7,  # replaced below
    }
    g = float(s.get("gravity", 9.81))
    for _ in range(3):  # the locked ball's f1 hardly depends on R: converged in two rounds
        f1 = float(fleet.frequencies(s, "locked")[0])
        s["ball"]["track_radius"] = r + g / (1.4 * (math.pi * f1) ** 2)
    return s


def lock_in_speed(scene: dict, f1: float) -> float:
    v = next(x for x in scene["loads"] if x["type"] == "vortex-shedding")
    return f1 * v["depth"] / v["strouhal"]


def record_scene(scene: dict, u_lock: float, seed: int, index: int, duration: float) -> dict:
    """The scene of record `index`: its climate drawn from (seed, index)."""
    rng = np.random.default_rng([seed, index])
    u = max(0.5, WEIBULL_SCALE * rng.weibull(WEIBULL_SHAPE))
    ti = TURBULENCE_MEDIAN * math.exp(TURBULENCE_LOG_SD * rng.standard_normal())
    s = json.loads(json.dumps(scene))
    loads = []
    for x in s["loads"]:
        if x["type"] == "buffeting":
            x.update(mean_speed=u, turbulence_intensity=ti)
            loads.append(x)
        elif x["type"] == "vortex-shedding":
            if abs(u / u_lock - 1.0) <= LOCK_IN_BAND and ti <= LOCK_IN_TURBULENCE:
                episodes = []
                for _ in range(int(rng.integers(1, 4))):
                    start = float(rng.uniform(0.0, duration))
                    episodes.append([start, min(duration, start + float(rng.uniform(30.0, 120.0)))])
                x.update(speed=u_lock, episodes=sorted(episodes))
                loads.append(x)
        elif x["type"] == "truck-gust":
            n = int(rng.poisson(TRUCKS_PER_HOUR * duration / 3600.0))
            x["times"] = sorted(float(t) for t in rng.uniform(0.0, max(duration - x["duration"], 0.0), n))
            loads.append(x)
        else:
            loads.append(x)
    s["loads"] = loads
    s["duration"] = duration
    return s


def tasks(records: int, seed: int, duration: float):
    """(scene, seed, duration, absorber) of every task: each record with and without the
    absorber (the same wind on both)."""
    bare = base_scene()
    damped = with_absorber(bare)
    f1 = float(fleet.frequencies(bare)[0])
    u_lock = lock_in_speed(bare, f1)
    out = []
    for i in range(records):
        s = record_scene(bare, u_lock, seed, i, duration)
        d = json.loads(json.dumps(s))
        d["tip"], d["ball"] = damped["tip"], damped["ball"]
        task_seed = seed * 1_000_003 + i
        out.append((s, task_seed, duration, "none"))
        out.append((d, task_seed, duration, "free"))
    return out, damped["ball"]["track_radius"]


def run_serial(work):
    return [fleet.record_tally(*t) for t in work]


def run_dask(work, scheduler=None, workers=None, quiet=False):
    from dask.distributed import Client, LocalCluster, as_completed, progress

    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1, processes=True)
        client = Client(cluster)
    try:
        if not quiet:
            print(f"dask: {client.dashboard_link or 'no dashboard'}; {len(work)} tasks", file=sys.stderr)
        futures = client.map(fleet.record_tally, *zip(*work), pure=False)
        if not quiet:
            progress(futures)
            print(file=sys.stderr)
        # Results in task order (tallies add exactly: the order only matters for the table).
        done = {f.key: f.result() for f in as_completed(futures)}
        return [done[f.key] for f in futures]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def summarize(tallies, work):
    none = sum((t for t, w in zip(tallies, work) if w[3] == "none"), fleet.DamageTally())
    free = sum((t for t, w in zip(tallies, work) if w[3] == "free"), fleet.DamageTally())
    return {"none": none, "free": free}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--records", type=int, default=128, help="wind records (each run with and without the absorber)")
    p.add_argument("--duration", type=float, default=600.0, help="length of a record [s]")
    p.add_argument("--seed", type=int, default=2024)
    p.add_argument("--scheduler", help="address of a Dask scheduler (tcp://host:8786); default: a LocalCluster here")
    p.add_argument("--workers", type=int, help="LocalCluster worker processes (default: all cores)")
    p.add_argument("--serial", action="store_true", help="run in this process, without Dask")
    p.add_argument("--out", help="write the result as JSON here")
    a = p.parse_args()
    if a.records < 2:
        p.error("invalid value for --records: at least 2 (a confidence interval needs a spread)")
    if not (a.duration > 0.0 and math.isfinite(a.duration)):
        p.error("invalid value for --duration: must be finite and positive")

    work, radius = tasks(a.records, a.seed, a.duration)
    t0 = time.perf_counter()
    tallies = run_serial(work) if a.serial else run_dask(work, a.scheduler, a.workers)
    wall = time.perf_counter() - t0
    result = summarize(tallies, work)
    hours = sum(float(t.seconds) for t in tallies) / 3600.0
    print(f"{a.records} records of {a.duration:g} s, each with and without the absorber "
          f"(ball {BALL_MASS:g} kg, track radius {radius:.3f} m): {hours:.1f} simulated hours in {wall:.1f} s")
    out = {"records": a.records, "duration": a.duration, "seed": a.seed, "track_radius": radius, "wall_s": wall}
    for name, label in [("none", "bare arm"), ("free", "with the absorber")]:
        t = result[name]
        for ext, what in [(False, "AASHTO cutoff at the CAFT"), (True, "S-N line extended below the CAFT")]:
            m, lo, hi = t.per_year(extended=ext)
            key = f"{name}_{'extended' if ext else 'cutoff'}"
            out[key] = {"per_year": m, "ci95": [lo, hi]}
            life = f"{1.0 / m:.3g} years" if m > 0 else "infinite"
            print(f"  {label:18s} damage per year ({what}): {m:.3e} (95 % CI {lo:.3e} … {hi:.3e}); life {life}")
        out[f"{name}_cycles_per_year"] = t.cycles() * fleet.SECONDS_PER_YEAR / float(t.seconds)
    if a.out:
        with open(a.out, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
