#!/usr/bin/env python3
"""Rainflow test vectors for absorber-core's streaming counter, from the Python `rainflow`
package (ASTM E1049-85 (2011) §5.4.4, https://pypi.org/project/rainflow/).

Regenerate (from the workspace root, with `pip install rainflow==3.2.0`):

    python3 scripts/rainflow_vectors.py > absorber-core/tests/data/rainflow_vectors.csv

Writes three seeded random sequences of 2000 points (values rounded to 6 decimals and
written with Python's round-trip repr, so Rust parses the same f64) and, for each, the package's `extract_cycles` output aggregated
by range: a sorted list of [range, count] with count in cycles (half cycles count 0.5),
residue included as half cycles at the end of the history (the package's convention, which
absorber-core's `Rainflow::residue` reproduces at any time).

`--check-eviction` instead runs the randomized check of the residue-overflow rule documented
in absorber-core/src/monitor/rainflow.rs (prints the smallest ratio of forced to true damage).
"""
import math
import random
import sys
from collections import defaultdict

import rainflow

SEED = 20240607
LENGTH = 2000


def sequences():
    rng = random.Random(SEED)
    out = []
    # 1: uniform white noise
    out.append(("uniform", [round(rng.uniform(-1.0, 1.0), 6) for _ in range(LENGTH)]))
    # 2: Gaussian random walk (long-range drift: large residue)
    x, walk = 0.0, []
    for _ in range(LENGTH):
        x += rng.gauss(0.0, 1.0)
        walk.append(round(x, 6))
    out.append(("random_walk", walk))
    # 3: narrow-band: a beating sine pair plus noise, like the tip stress of the absorber
    nb = []
    for k in range(LENGTH):
        t = k * 0.003
        envelope = 20.0 * (1.0 + 0.5 * math.sin(2.0 * math.pi * t / 3.9))
        v = envelope * math.sin(2.0 * math.pi * 4.13 * t) + rng.gauss(0.0, 0.5)
        nb.append(round(v, 6))
    out.append(("beating_sine_noise", nb))
    return out


def counts(series):
    agg = defaultdict(float)
    for rng_, _mean, count, _i, _j in rainflow.extract_cycles(series):
        agg[rng_] += count
    return [[r, c] for r, c in sorted(agg.items())]


def check_eviction(trials=20000, m=3.0):
    def dmg(seq):
        return sum(c * r ** m for r, c in rainflow.count_cycles(seq))

    def residue(seq):
        pts = []
        for _, x in rainflow.reversals(seq):
            pts.append(x)
            while len(pts) >= 3:
                X, Y = abs(pts[-1] - pts[-2]), abs(pts[-2] - pts[-3])
                if X < Y:
                    break
                if len(pts) == 3:
                    pts.pop(0)
                else:
                    last = pts.pop(); pts.pop(); pts.pop(); pts.append(last)
        return pts

    rng = random.Random(1)
    worst = float("inf")
    for _ in range(trials):
        n = rng.randint(5, 12)
        a, c, seq = rng.uniform(5, 10), rng.uniform(-1, 1), []
        for k in range(n):
            a *= rng.uniform(0.6, 0.99)
            seq.append(c + (a if k % 2 else -a))
        res = residue(seq)
        if len(res) < 5:
            continue
        cont = [rng.uniform(-15, 15) * rng.random() for _ in range(rng.randint(0, 8))]
        true = dmg(res + cont)
        forced = abs(res[1] - res[2]) ** m + dmg(res[:2] + res[4:] + cont)
        if true > 0:
            worst = min(worst, forced / true)
    print(f"eviction rule: min forced/true damage over {trials} trials = {worst:.6f}")


def main():
    if "--check-eviction" in sys.argv:
        check_eviction()
        return
    out = sys.stdout
    out.write("# Rainflow test vectors from the Python `rainflow` package %s (ASTM E1049-85 §5.4.4).\n" % rainflow.__version__)
    out.write("# Regenerate: python3 scripts/rainflow_vectors.py > absorber-core/tests/data/rainflow_vectors.csv\n")
    out.write("# seed %d. Per sequence two lines:\n" % SEED)
    out.write("#   series,<name>,x0,x1,...            (the samples, repr of f64)\n")
    out.write("#   counts,<name>,r0,c0,r1,c1,...      (distinct ranges ascending, cycles; residue as 1/2 cycles)\n")
    for name, s in sequences():
        out.write("series,%s,%s\n" % (name, ",".join(repr(x) for x in s)))
        out.write("counts,%s,%s\n" % (name, ",".join("%r,%r" % (r, c) for r, c in counts(s))))


if __name__ == "__main__":
    main()
