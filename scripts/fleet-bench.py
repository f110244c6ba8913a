#!/usr/bin/env python3
"""Throughput of the fleet study (examples/python/fleet_study.py) here: serial against Dask
workers, for docs/fleet.md.

The same tasks (records of the mast arm with and without the absorber) run in rounds; each
round runs, in turn, the serial loop (one process, no Dask), a LocalCluster of one worker and
one of two workers (threads_per_worker = 1; clusters started and warmed before the clock
starts). The machine is shared, so the configurations are interleaved within every round and
the figures are medians over rounds of per-round (paired) ratios. Also the per-task overhead
of Dask (tasks of one step each), the CPU time the work took (this process, or the workers'
processes: what contention from other jobs does not inflate) and the projected wall time of
10^6 simulated hours.

Usage: python scripts/fleet-bench.py [--records 16] [--rounds 5] [--json docs/fleet.json]
(needs the absorber package and dask[distributed]; prints a markdown table).
"""

import argparse
import importlib.util
import json
import os
import statistics
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def study():
    spec = importlib.util.spec_from_file_location(
        "fleet_study", os.path.join(ROOT, "examples", "python", "fleet_study.py")
    )
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--records", type=int, default=16, help="records per round (each with and without the absorber)")
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--json", help="write the figures here")
    a = p.parse_args()

    from dask.distributed import Client, LocalCluster

    from absorber import fleet

    s = study()
    work, _ = s.tasks(a.records, seed=99, duration=a.duration)
    hours = len(work) * a.duration / 3600.0
    tiny, _ = s.tasks(a.records, seed=98, duration=0.01)  # one step each: the task overhead

    clusters = {}
    for n in (1, 2):
        c = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        cl = Client(c)
        cl.gather(cl.map(fleet.record_tally, *zip(*tiny[: 2 * n]), pure=False))  # warm the workers
        clusters[n] = (c, cl)

    cpu = {"serial": [], "dask1": [], "dask2": []}

    def serial(w, key=None):
        t, c = time.perf_counter(), time.process_time()
        r = [fleet.record_tally(*x) for x in w]
        if key:
            cpu[key].append(time.process_time() - c)
        return time.perf_counter() - t, r

    def dask(n, w, key=None):
        cl = clusters[n][1]
        c0 = cl.run(time.process_time)
        t = time.perf_counter()
        r = cl.gather(cl.map(fleet.record_tally, *zip(*w), pure=False))
        wall = time.perf_counter() - t
        c1 = cl.run(time.process_time)
        if key:
            cpu[key].append(sum(c1[k] - c0[k] for k in c1))
        return wall, r

    rounds = []
    load0 = os.getloadavg()
    for k in range(a.rounds):
        row = {}
        row["serial"], ref = serial(work, "serial")
        row["dask1"], r1 = dask(1, work, "dask1")
        row["dask2"], r2 = dask(2, work, "dask2")
        if not (r1 == ref and r2 == ref):
            sys.exit("FAILED: Dask results differ from the serial ones")
        row["tiny_serial"], _ = serial(tiny)
        row["tiny_dask1"], _ = dask(1, tiny)
        rounds.append(row)
        print(f"round {k + 1}: " + ", ".join(f"{k2} {v:.2f} s" for k2, v in row.items()), file=sys.stderr)
    load1 = os.getloadavg()
    for c, cl in clusters.values():
        cl.close()
        c.close()

    med = lambda f: statistics.median(f(r) for r in rounds)  # noqa: E731
    per_core = {
        "serial": med(lambda r: hours / (r["serial"] / 3600.0)),
        "dask1": med(lambda r: hours / (r["dask1"] / 3600.0)),
        "dask2": med(lambda r: hours / (2 * r["dask2"] / 3600.0)),
    }
    worker_vs_serial = med(lambda r: r["serial"] / r["dask1"])
    worker2_vs_serial = med(lambda r: r["serial"] / (2 * r["dask2"]))
    scaling = med(lambda r: r["dask1"] / r["dask2"])
    overhead = med(lambda r: (r["tiny_dask1"] - r["tiny_serial"]) / len(tiny))
    record_s = med(lambda r: r["serial"] / len(work))
    cpu_rate = {k: statistics.median(hours / (c / 3600.0) for c in v) for k, v in cpu.items()}
    core_hours = 1e6 / per_core["dask2"]
    cpu_core_hours = 1e6 / cpu_rate["dask2"]
    out = {
        "records_per_round": len(work),
        "record_seconds_simulated": a.duration,
        "rounds": rounds,
        "load_average_before_after": [load0, load1],
        "simulated_hours_per_core_hour": per_core,
        "simulated_hours_per_cpu_hour": cpu_rate,
        "cpu_seconds": cpu,
        "dask_one_worker_over_serial": worker_vs_serial,
        "dask_two_workers_per_worker_over_serial": worker2_vs_serial,
        "scaling_one_to_two_workers": scaling,
        "task_overhead_s": overhead,
        "serial_seconds_per_record": record_s,
        "core_hours_for_1e6_simulated_hours": core_hours,
        "wall_hours_1e6_on_64_cores": core_hours / 64,
        "wall_hours_1e6_on_1024_cores": core_hours / 1024,
        "cpu_hours_for_1e6_simulated_hours": cpu_core_hours,
        "wall_hours_1e6_on_64_cores_cpu_rate": cpu_core_hours / 64,
        "wall_hours_1e6_on_1024_cores_cpu_rate": cpu_core_hours / 1024,
    }
    print(f"| figure | value |\n|---|---:|")
    print(f"| tasks per round (records × 2 absorber variants), simulated time each | {len(work)} × {a.duration:g} s |")
    print(f"| rounds (interleaved: serial, 1 worker, 2 workers) | {a.rounds} |")
    print(f"| serial wall time per record (median) | {record_s:.3f} s |")
    print(f"| simulated hours per core-hour: serial / Dask 1 worker / Dask 2 workers | {per_core['serial']:.0f} / {per_core['dask1']:.0f} / {per_core['dask2']:.0f} |")
    print(f"| Dask throughput per worker over serial (1 worker; 2 workers) | {worker_vs_serial:.3f}; {worker2_vs_serial:.3f} |")
    print(f"| simulated hours per CPU-hour (CPU time of the process, of the workers): serial / Dask 1 worker / Dask 2 workers | {cpu_rate['serial']:.0f} / {cpu_rate['dask1']:.0f} / {cpu_rate['dask2']:.0f} |")
    print(f"| … per-worker CPU efficiency over serial (1 worker; 2 workers) | {cpu_rate['dask1'] / cpu_rate['serial']:.3f}; {cpu_rate['dask2'] / cpu_rate['serial']:.3f} |")
    print(f"| scaling from 1 to 2 workers | {scaling:.3f}× |")
    print(f"| Dask overhead per task (one-step tasks, 1 worker minus serial) | {1e3 * overhead:.2f} ms |")
    print(f"| 10⁶ simulated hours: core-hours at the 2-worker wall-clock rate here | {core_hours:.0f} (64 cores: {core_hours / 64:.1f} h, 1,024 cores: {core_hours / 1024:.2f} h) |")
    print(f"| 10⁶ simulated hours: CPU-hours at the 2-worker CPU rate (a core of one's own) | {cpu_core_hours:.0f} (64 cores: {cpu_core_hours / 64:.1f} h, 1,024 cores: {cpu_core_hours / 1024:.2f} h) |")
    print(f"| load average before / after (1, 5, 15 min) | {load0[0]:.1f} {load0[1]:.1f} {load0[2]:.1f} / {load1[0]:.1f} {load1[1]:.1f} {load1[2]:.1f} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
