#!/usr/bin/env python3
"""Checks the FMUs of `host-sim fmu` with FMPy (run by scripts/fmu-test.sh, in CI).

1. `fmpy.validation.validate_fmu` finds no problem in the FMI 3.0 and the FMI 2.0 FMU.
2. An FMPy simulation of each FMU (`fmpy.simulate_fmu`) under the scene's harmonic base
   acceleration prints the same digits as the CSV of `host-sim run` of the same scene, in
   every row of every compared column.
3. A state taken in mid-run, serialized, deserialized into a fresh instance and continued,
   and the same state restored in memory, give the uninterrupted run bit for bit.
4. Bad input is refused with a clear status and log message naming it: a communication step
   that is not k·h, a bad parameter (`beam.modulus`), a non-finite input.

Usage: fmu-check.py --fmu3 a3.fmu --fmu2 a2.fmu --csv run/paper.csv --amplitude A --frequency F
"""

import argparse
import csv
import math
import sys

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

# Columns of `host-sim run`'s CSV and the FMU outputs they are compared with.
COLUMNS = {
    "tip_deflection": "tip_deflection",
    "ball_angle": "ball_angle",
    "ball_rel_angle": "ball_relative_angle",
    "normal_force": "normal_force",
}


def harmonic(k, amplitude, frequency, h):
    """The base acceleration of grid point k, computed as host-sim computes it
    (`Excitation::harmonic`: -A w^2 sin(w k h), w = 2 pi f; the same libm `sin`)."""
    w = math.tau * frequency
    return -amplitude * w * w * math.sin(w * k * h)


def printed(x):
    """`x` as host-sim's CSV prints it (Rust's `{:.9e}`: 10 significant digits)."""
    if math.isnan(x):
        return "NaN"
    mantissa, exponent = f"{x:.9e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def input_signal(n, amplitude, frequency, h):
    """FMPy input table for n steps. The FMU holds an input over the communication step and
    applies it at the step's end, so the value set at t_k is the sample of t_(k+1). At t = 0
    the table has an event: the value before it (sample 0) is what initialization sees, the
    value after it (sample 1) what the first step sees."""
    a = [harmonic(k, amplitude, frequency, h) for k in range(n + 1)]
    times = [-h, 0.0] + [k * h for k in range(n)]
    values = [a[0], a[0]] + a[1 : n + 1]
    signal = np.zeros(
        len(times), dtype=[("time", np.float64), ("base_acceleration", np.float64), ("tip_load", np.float64)]
    )
    signal["time"] = np.array(times)
    signal["time"][2:] = np.arange(n) * h  # k h exactly as FMPy's time grid (k · h)
    signal["base_acceleration"] = values
    return signal, a


def read_csv(path):
    rows = [r for r in csv.reader(line for line in open(path) if not line.startswith("#"))]
    header, data = rows[0], rows[1:]
    return {name: [r[i] for r in data] for i, name in enumerate(header)}


def check_validation(paths):
    ok = True
    for p in paths:
        problems = validate_fmu(p)
        print(f"fmpy.validate_fmu({p}): {len(problems)} problems" + "".join(f"\n  {x}" for x in problems))
        ok &= not problems
    return ok


def check_run(path, run, amplitude, frequency):
    md = read_model_description(path)
    h = float(md.defaultExperiment.stepSize)
    n = len(run["t"]) - 1
    signal, a = input_signal(n, amplitude, frequency, h)
    # The inputs are the samples host-sim used (its CSV prints them).
    assert all(printed(x) == y for x, y in zip(a, run["base_accel"])), "harmonic samples differ from the CSV"
    result = simulate_fmu(
        path,
        start_time=0.0,
        stop_time=n * h,
        output_interval=h,
        input=signal,
        output=list(COLUMNS.values()) + ["contact"],
    )
    if len(result) != n + 1:
        print(f"{path}: {len(result)} rows, the CSV has {n + 1}")
        return False
    worst = {}
    mismatches = 0
    for col, var in COLUMNS.items():
        got = [printed(float(x)) for x in result[var]]
        bad = [k for k, (x, y) in enumerate(zip(got, run[col])) if x != y]
        mismatches += len(bad)
        worst[col] = max(abs(float(x) - float(y)) for x, y in zip(result[var], run[col]))
        if bad:
            k = bad[0]
            print(f"  {col}: {len(bad)} rows differ, first at t = {run['t'][k]}: FMU {got[k]} CSV {run[col][k]}")
    contact = ["0" if c == 2 else "1" for c in result["contact"]]
    bad_contact = sum(x != y for x, y in zip(contact, run["contact"]))
    mismatches += bad_contact
    print(
        f"{path} (FMI {md.fmiVersion}): {n} steps of {h} s, FMPy vs host-sim run: "
        f"{mismatches} of {(len(COLUMNS) + 1) * (n + 1)} printed values differ; largest |difference| "
        + ", ".join(f"{c} {w:.1e}" for c, w in worst.items())
    )
    return mismatches == 0


class Fmu:
    """The low-level FMPy instance of either version, with its log captured."""

    def __init__(self, path, name):
        self.md = read_model_description(path)
        self.dir = extract(path)
        self.v3 = self.md.fmiVersion == "3.0"
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.h = float(self.md.defaultExperiment.stepSize)
        self.log = []
        kw = dict(
            guid=self.md.guid,
            unzipDirectory=self.dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        if self.v3:
            self.f = FMU3Slave(**kw)
            self.f.instantiate(logMessage=lambda env, status, cat, msg: self.log.append(msg.decode()))
        else:
            self.f = FMU2Slave(**kw)
            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(lambda env, inst, status, cat, msg: self.log.append(msg.decode()))
            self.callbacks = cb
            self.f.instantiate(callbacks=cb)
            self.f.setupExperiment(startTime=0.0)

    def start(self, a0=0.0, **params):
        if params:
            self.set(**params)
        self.f.enterInitializationMode()
        self.set(base_acceleration=a0)
        self.f.exitInitializationMode()

    def set(self, **values):
        vrs = [self.vr[k.replace("__", ".")] for k in values]
        (self.f.setFloat64 if self.v3 else self.f.setReal)(vrs, list(values.values()))

    def get(self, *names):
        return (self.f.getFloat64 if self.v3 else self.f.getReal)([self.vr[n] for n in names])

    def step(self, t, dt):
        self.f.doStep(t, dt)

    def state(self):
        return self.f.getFMUState() if self.v3 else self.f.getFMUstate()

    def restore(self, s):
        (self.f.setFMUState if self.v3 else self.f.setFMUstate)(s)

    def serialize(self, s):
        return self.f.serializeFMUState(s) if self.v3 else self.f.serializeFMUstate(s)

    def deserialize(self, b):
        return self.f.deserializeFMUState(b) if self.v3 else self.f.deSerializeFMUstate(b)


def run_steps(fmu, k0, k1, a):
    """Steps k0+1 … k1 with the samples a; the outputs' bits after each step."""
    out = []
    for k in range(k0, k1):
        fmu.set(base_acceleration=a[k + 1])
        fmu.step(k * fmu.h, fmu.h)
        out.append(tuple(x.hex() for x in fmu.get("tip_deflection", "root_stress", "damage", "ball_angle")))
    return out


def check_state(path, amplitude, frequency):
    a_ = Fmu(path, "a")
    n, mid = 20000, 10000
    a = [harmonic(k, amplitude, frequency, a_.h) for k in range(n + 1)]
    a_.start(a[0])
    run_steps(a_, 0, mid, a)
    s = a_.state()
    blob = a_.serialize(s)
    reference = run_steps(a_, mid, n, a)
    a_.restore(s)
    in_memory = run_steps(a_, mid, n, a)
    b = Fmu(path, "b")
    b.start(a[0])
    b.restore(b.deserialize(blob))
    restored = run_steps(b, mid, n, a)
    ok = in_memory == reference and restored == reference
    print(
        f"{path}: state at t = {mid * a_.h:g} s ({len(blob)} bytes serialized), {n - mid} more steps: "
        f"in-memory restore {'identical' if in_memory == reference else 'DIFFERS'}, "
        f"serialized into a fresh instance {'identical' if restored == reference else 'DIFFERS'} bit for bit"
    )
    return ok


def refused(fmu, call, needle):
    try:
        call()
    except Exception as e:  # FMPy raises on a status above Warning
        msg = next((m for m in reversed(fmu.log) if needle in m), None)
        print(f"  refused ({e}); log: {msg}")
        return msg is not None
    print("  NOT refused")
    return False


def check_errors(path):
    ok = True
    f = Fmu(path, "wrong-step")
    f.start()
    ok &= refused(f, lambda: f.step(0.0, 1.5 * f.h), "not a whole multiple")
    f = Fmu(path, "bad-parameter")
    ok &= refused(f, lambda: f.start(beam__modulus=-1.0), "`beam.modulus`")
    f = Fmu(path, "bad-input")
    f.start()
    f.set(base_acceleration=float("nan"))
    ok &= refused(f, lambda: f.step(0.0, f.h), "`base_acceleration`")
    print(f"{path}: bad communication step, parameter and input refused with their names: {'yes' if ok else 'NO'}")
    return ok


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fmu3", required=True)
    p.add_argument("--fmu2", required=True)
    p.add_argument("--csv", required=True, help="host-sim run's CSV of the same scene")
    p.add_argument("--amplitude", type=float, required=True, help="the scene's excitation.amplitude [m]")
    p.add_argument("--frequency", type=float, required=True, help="the scene's excitation.frequency [Hz]")
    a = p.parse_args()
    run = read_csv(a.csv)
    ok = check_validation([a.fmu3, a.fmu2])
    for path in (a.fmu3, a.fmu2):
        ok &= check_run(path, run, a.amplitude, a.frequency)
        ok &= check_state(path, a.amplitude, a.frequency)
        ok &= check_errors(path)
    print("fmu checks: " + ("all passed" if ok else "FAILED"))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
