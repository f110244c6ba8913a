#!/usr/bin/env python3
"""Bad input to every command of the command line, tried from outside, each outcome classified.

Each case runs `host-sim` with a bad value (missing or unknown keys, wrong types, NaN, inf,
negative, zero, huge, out-of-range choices, empty or garbage CSV, other separators, option
combinations, negative numbers as option values, overrides that make a scene invalid) and is
classified as one of

  clear      refused (exit 1 or 2) with one line that names the key or option, its value and
             what is allowed (a range, a limit or the possible values)
  unclear    refused, but the message misses the key, the value or what is allowed
  wrong      exit 0 on an input that has no meaningful answer (silently wrong)
  abort      killed by a signal, exit 101 (a panic) or another code, or no answer within the
             time limit (a hang)
  lost       a failed command changed or removed the outputs of an earlier good one
  ok         a valid edge case that ran (exit 0), as expected

With `--python PY` (an interpreter that imports the `absorber` package, e.g. the venv of
scripts/python-test.sh), the Python bindings get the same kind of cases: an `AbsorberError`
(or `TypeError`) naming the key and value is clear; a crash of the interpreter is an abort.

Usage: scripts/error-matrix.py [--bin target/release/host-sim]
       [--studies-bin target/release/absorber-studies] [--python PY] [--jobs 2]
       [--only WORD] [--verbose]. The studies' cases (`stability`, `accuracy`, `validation`,
       `chaos`) run the developer tool `absorber-studies`. Prints one line per case that is not clear or ok and the
counts; exits 1 when any case is wrong, abort or lost, or more than `--max-unclear` (default 0)
are unclear. Takes well under a minute on two cores (most cases are refused before any work).
"""
import argparse
import concurrent.futures
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile

# What a message must say besides the key and the value: what is allowed.
ALLOWED = re.compile(
    r"must|between|at least|at most|allowed|one of|expected|range|≤|≥|<|>|positive|finite|"
    r"non-negative|greater|less|within|needs|possible values|exceeds|above|below|limit|"
    r"maximum|minimum|only|integer|a number|a string|a table|an array|not a|no more|no less|"
    r"supported|supports|known|no response|exists|no such|not found|permission|columns:",
    re.I,
)

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER_SCENE = os.path.join(REPO, "scenes", "paper.toml")
ARM_SCENE = os.path.join(REPO, "scenes", "mast-arm.toml")


class Case:
    """One command line; `names` are the words the message must hold (the key or option and
    its value; each entry a `|`-separated list of alternatives)."""

    def __init__(self, name, args, names=(), expect="error", files=None, timeout=60, lost=None,
                 fsize=None):
        # Commands with required options get them (the case is about the other one).
        if args and args[0] == "fmu" and "--out" not in args:
            args = args + ["--fmi-version", "3", "--out", "x.fmu"]
        if args and args[0] == "calibrate" and "--out" not in args:
            args = args + ["--out", "c.toml"]
        self.name = name
        self.args = args
        self.names = names
        self.expect = expect
        self.files = files or {}
        self.timeout = timeout
        self.lost = lost
        # A file-size limit (`ulimit -f`, bytes) for the failing command.
        self.fsize = fsize


def scene_with(base, extra):
    """The shipped scene `base` with `extra` appended (later keys of TOML tables win only when
    written as their own table; `extra` replaces a whole key by editing the text)."""
    return ("@" + base, extra)


def cases():
    c = []
    add = c.append
    # ---- option values on the common scene options (every command that takes them).
    for cmd in ["paper", "run", "sweep", "fatigue", "static", "modes", "tune", "calibrate", "fmu"]:
        quick = ["--duration", "0.5"] if cmd in ("paper", "run", "sweep", "fatigue") else []
        add(Case(f"{cmd} --elements 5", [cmd, "--elements", "5"] + quick, ["elements", "5"]))
        add(Case(f"{cmd} --elements 0", [cmd, "--elements", "0"] + quick, ["elements", "0"]))
        add(Case(f"{cmd} --elements -3", [cmd, "--elements", "-3"] + quick, ["elements", "-3"]))
        add(Case(f"{cmd} --kind bogus", [cmd, "--kind", "bogus"], ["kind", "bogus"]))
        add(Case(f"{cmd} --precision f16", [cmd, "--precision", "f16"], ["precision", "f16"]))
        add(Case(f"{cmd} --scene missing", [cmd, "--scene", "no-such.toml"], ["no-such.toml"]))
        add(Case(f"{cmd} unknown option", [cmd, "--bogus", "1"], ["--bogus"]))
    for cmd in ["paper", "run", "sweep", "fatigue", "fmu"]:
        for opt, v in [
            ("--duration", "nan"),
            ("--duration", "-1"),
            ("--duration", "0"),
            ("--duration", "inf"),
            ("--duration", "1e300"),
            ("--step", "0"),
            ("--step", "-1e-3"),
            ("--step", "nan"),
            ("--step", "10"),
            ("--frequency", "0"),
            ("--frequency", "-4"),
            ("--frequency", "1e6"),
            ("--frequency", "abc"),
            ("--amplitude", "nan"),
            ("--amplitude", "inf"),
            ("--amplitude", "1e300"),
        ]:
            add(Case(f"{cmd} {opt} {v}", [cmd, opt, v], [opt.lstrip("-"), v]))
        # A negative amplitude parses (it is a value, not an option) and is refused by name.
        add(Case(f"{cmd} --amplitude -1e-3", [cmd, "--amplitude", "-1e-3", "--duration", "0.2"],
                 ["amplitude", "-1e-3"]))
    # ---- run
    add(Case("run --every 0", ["run", "--every", "0", "--duration", "0.2"], ["every", "0"]))
    add(Case("run --every -1", ["run", "--every", "-1"], ["every", "-1"]))
    add(Case("run --transient -1", ["run", "--transient", "-1"], ["transient", "-1"]))
    add(Case("run --transient nan", ["run", "--transient", "nan"], ["transient", "nan|NaN"]))
    add(Case("run --transient past the end", ["run", "--transient", "100", "--duration", "1"],
             ["transient", "100"]))
    add(Case("run --ensemble 0", ["run", "--ensemble", "0"], ["ensemble", "0"]))
    add(Case("run --ensemble -2", ["run", "--ensemble", "-2"], ["ensemble", "-2"]))
    add(Case("run --ensemble 1e9", ["run", "--ensemble", "1000000000"], ["ensemble", "1000000000"]))
    add(Case("run --seed -1", ["run", "--seed", "-1"], ["seed", "-1"]))
    add(Case("run --plots bogus", ["run", "--plots", "bogus"], ["plots", "bogus"]))
    add(Case("run --solver bogus", ["run", "--solver", "bogus"], ["solver", "bogus"]))
    add(Case("run --out is a file", ["run", "--duration", "0.2", "--out", "FILE:afile"],
             ["afile"], files={"afile": "x"}))
    add(Case("run --duration 1e7 (steps)", ["run", "--duration", "1e7"], ["duration", "1e7|10000000"]))
    add(Case("run full --elements 0", ["run", "--solver", "full", "--elements", "0"],
             ["elements", "0"]))
    add(Case("run full --elements 100000", ["run", "--solver", "full", "--elements", "100000"],
             ["elements", "100000"]))
    # ---- sweep
    add(Case("sweep --freqs -1,4", ["sweep", "--freqs", "-1,4", "--duration", "0.5"],
             ["freqs|frequency", "-1"]))
    add(Case("sweep --freqs nan", ["sweep", "--freqs", "nan"], ["freqs|frequency", "nan|NaN"]))
    add(Case("sweep --freqs empty", ["sweep", "--freqs", ""], ["freqs"]))
    add(Case("sweep --freqs a,b", ["sweep", "--freqs", "a,b"], ["freqs", "a"]))
    add(Case("sweep --freqs 0", ["sweep", "--freqs", "0"], ["freqs|frequency", "0"]))
    add(Case("sweep --jobs 0", ["sweep", "--jobs", "0", "--duration", "0.5"], ["jobs", "0"]))
    add(Case("sweep --jobs -1", ["sweep", "--jobs", "-1"], ["jobs", "-1"]))
    add(Case("sweep --jobs 1000000", ["sweep", "--jobs", "1000000", "--duration", "0.5",
                                      "--no-plots", "--freqs", "4.1,4.13"], expect="ok"))
    add(Case("sweep --last 0", ["sweep", "--last", "0", "--duration", "0.5"], ["last", "0"]))
    add(Case("sweep --last -1", ["sweep", "--last", "-1"], ["last", "-1"]))
    add(Case("sweep --last past the run", ["sweep", "--last", "10", "--duration", "1"],
             ["last", "10"]))
    add(Case("sweep --ensemble 0", ["sweep", "--ensemble", "0"], ["ensemble", "0"]))
    # ---- fatigue
    add(Case("fatigue --category Z", ["fatigue", "--category", "Z"], ["category", "Z"]))
    add(Case("fatigue --amplitudes -1", ["fatigue", "--amplitudes", "-1e-3"],
             ["amplitudes|amplitude", "-0.001|-1e-3"]))
    add(Case("fatigue --amplitudes nan", ["fatigue", "--amplitudes", "nan"],
             ["amplitudes|amplitude", "nan|NaN"]))
    add(Case("fatigue --moment bogus", ["fatigue", "--moment", "bogus"], ["moment", "bogus"]))
    add(Case("fatigue --calibrate-against 0", ["fatigue", "--calibrate-against", "0"],
             ["calibrate-against", "0"]))
    add(Case("fatigue --freqs 0", ["fatigue", "--freqs", "0"], ["freqs|frequency", "0"]))
    add(Case("fatigue --jobs 0", ["fatigue", "--jobs", "0"], ["jobs", "0"]))
    # ---- modes / static / tune
    add(Case("modes --count 0", ["modes", "--count", "0"], ["count", "0"]))
    add(Case("modes --count -1", ["modes", "--count", "-1"], ["count", "-1"]))
    add(Case("modes --count 1e9", ["modes", "--count", "1000000000"], expect="ok"))
    add(Case("tune --ratio 0", ["tune", "--ratio", "0"], ["ratio", "0"]))
    add(Case("tune --ratio -0.5", ["tune", "--ratio", "-0.5"], ["ratio", "-0.5"]))
    add(Case("tune --ratio nan", ["tune", "--ratio", "nan"], ["ratio", "nan|NaN"]))
    add(Case("tune --ratio 100", ["tune", "--ratio", "100"], ["ratio", "100"]))
    # Missing directories of an output are created.
    add(Case("tune --write into a missing dir", ["tune", "--write", "no/such/dir/t.toml"],
             expect="ok"))
    # ---- calibrate
    add(Case("calibrate --reference-elements 1", ["calibrate", "--reference-elements", "1"],
             ["reference-elements", "1"]))
    add(Case("calibrate --reference-elements 0", ["calibrate", "--reference-elements", "0"],
             ["reference-elements", "0"]))
    add(Case("calibrate --reference-elements -1", ["calibrate", "--reference-elements", "-1"],
             ["reference-elements", "-1"]))
    add(Case("calibrate --target-f1 -1", ["calibrate", "--target-f1", "-1"], ["target-f1", "-1"]))
    add(Case("calibrate --target-f1 nan", ["calibrate", "--target-f1", "nan"],
             ["target-f1", "nan|NaN"]))
    add(Case("calibrate --target-f1 0", ["calibrate", "--target-f1", "0"], ["target-f1", "0"]))
    add(Case("calibrate --target-f1 1e6", ["calibrate", "--target-f1", "1e6"],
             ["target-f1", "1e6|1000000"]))
    add(Case("calibrate --target-zeta -0.01", ["calibrate", "--target-f1", "4.1",
                                               "--target-zeta", "-0.01"], ["target-zeta", "-0.01"]))
    add(Case("calibrate --target-zeta 2", ["calibrate", "--target-f1", "4.1",
                                           "--target-zeta", "2"], ["target-zeta", "2"]))
    add(Case("calibrate --from-identified missing", ["calibrate", "--from-identified",
                                                     "none.toml"], ["none.toml"]))
    add(Case("calibrate --from-identified garbage", ["calibrate", "--from-identified",
                                                     "FILE:id.toml"], ["id.toml"],
             files={"id.toml": "this is = = not toml\n"}))
    add(Case("calibrate --from-identified empty", ["calibrate", "--from-identified",
                                                   "FILE:id.toml"], ["id.toml"],
             files={"id.toml": ""}))
    add(Case("calibrate --from-identified f1 negative", ["calibrate", "--from-identified",
                                                         "FILE:id.toml"], ["f1", "-4"],
             files={"id.toml": "f1 = -4.0\nzeta = 0.003\nusable = true\n"}))
    add(Case("calibrate --from-identified + --target-f1", ["calibrate", "--from-identified",
                                                            "FILE:id.toml", "--target-f1", "4"],
             ["from-identified|target-f1"], files={"id.toml": "f1 = 4.0\n"}))
    # ---- identify
    decay = "t,tip_acceleration\n" + "".join(
        f"{i * 0.002},{__import__('math').exp(-0.08 * i * 0.002) * __import__('math').sin(25.8 * i * 0.002)}\n"
        for i in range(4000))
    add(Case("identify no --csv", ["identify"], ["csv"]))
    add(Case("identify missing file", ["identify", "--csv", "no-such.csv"], ["no-such.csv"]))
    add(Case("identify empty file", ["identify", "--csv", "FILE:e.csv"], ["e.csv"],
             files={"e.csv": ""}))
    add(Case("identify header only", ["identify", "--csv", "FILE:h.csv"], ["h.csv"],
             files={"h.csv": "t,tip_acceleration\n"}))
    add(Case("identify garbage", ["identify", "--csv", "FILE:g.csv"], ["g.csv"],
             files={"g.csv": "\x00\x01garbage\xff\n1,2,3\n"}))
    add(Case("identify no such column", ["identify", "--csv", "FILE:d.csv", "--column", "zz"],
             ["zz"], files={"d.csv": decay}))
    add(Case("identify no such time column", ["identify", "--csv", "FILE:d.csv",
                                              "--time-column", "zz"], ["zz"],
             files={"d.csv": decay}))
    add(Case("identify text in a cell", ["identify", "--csv", "FILE:d.csv"], ["d.csv", "abc"],
             files={"d.csv": decay.replace("\n0.01,", "\nabc,", 1)
                    if "\n0.01," in decay else decay[:40] + "abc,1\n" + decay[40:]}))
    add(Case("identify nan sample", ["identify", "--csv", "FILE:d.csv"], ["d.csv", "nan|NaN"],
             files={"d.csv": decay.replace("\n0.02,", "\n0.02,nan\n0.0201,", 1)}))
    add(Case("identify time going back", ["identify", "--csv", "FILE:d.csv"], ["d.csv", "t"],
             files={"d.csv": "t,tip_acceleration\n0,0\n0.002,1\n0.001,0\n" * 1}))
    add(Case("identify --band 5,1", ["identify", "--csv", "FILE:d.csv", "--band", "5,1"],
             ["band", "5"], files={"d.csv": decay}))
    add(Case("identify --band -1,5", ["identify", "--csv", "FILE:d.csv", "--band", "-1,5"],
             ["band", "-1"], files={"d.csv": decay}))
    add(Case("identify --band abc", ["identify", "--csv", "FILE:d.csv", "--band", "abc"],
             ["band", "abc"], files={"d.csv": decay}))
    add(Case("identify --band 1", ["identify", "--csv", "FILE:d.csv", "--band", "1"],
             ["band", "1"], files={"d.csv": decay}))
    add(Case("identify --band 300,400", ["identify", "--csv", "FILE:d.csv", "--band", "300,400"],
             ["band", "300"], files={"d.csv": decay}))
    add(Case("identify --record bogus", ["identify", "--csv", "FILE:d.csv", "--record", "x"],
             ["record", "x"], files={"d.csv": decay}))
    add(Case("identify constant", ["identify", "--csv", "FILE:c.csv"], ["c.csv|signal"],
             files={"c.csv": "t,tip_acceleration\n" + "".join(f"{i*0.002},1\n" for i in range(2000))}))
    add(Case("identify semicolons", ["identify", "--csv", "FILE:s.csv"], expect="ok",
             files={"s.csv": decay.replace(",", ";")}))
    add(Case("identify BOM", ["identify", "--csv", "FILE:b.csv"], expect="ok",
             files={"b.csv": "\ufeff" + decay}))
    add(Case("identify --out into a missing dir", ["identify", "--csv", "FILE:d.csv", "--out",
                                                   "no/such/dir/x.toml"], expect="ok",
             files={"d.csv": decay}))
    # ---- estimate
    add(Case("estimate --duration 1e9", ["estimate", "--lab", "--duration", "1e9"],
             ["duration", "1e9|1000000000"]))
    add(Case("estimate arm --duration 1e9", ["estimate", "--scene", ARM_SCENE, "--duration",
                                             "1e9"], ["duration", "1e9|1000000000"]))
    add(Case("estimate --duration 0.01", ["estimate", "--lab", "--duration", "0.01"],
             ["duration", "0.01"]))
    add(Case("estimate --duration -1", ["estimate", "--lab", "--duration", "-1"],
             ["duration", "-1"]))
    add(Case("estimate --duration nan", ["estimate", "--lab", "--duration", "nan"],
             ["duration", "nan|NaN"]))
    add(Case("estimate --frequency 400", ["estimate", "--lab", "--frequency", "400"],
             ["frequency", "400"]))
    add(Case("estimate --frequency -1", ["estimate", "--lab", "--frequency", "-1"],
             ["frequency", "-1"]))
    add(Case("estimate --frequency without --lab", ["estimate", "--frequency", "4"],
             ["frequency", "lab"]))
    add(Case("estimate --tip-force nan", ["estimate", "--lab", "--tip-force", "nan"],
             ["tip-force", "nan|NaN"]))
    add(Case("estimate --tip-force -1", ["estimate", "--lab", "--tip-force", "-1"],
             ["tip-force", "-1"]))
    add(Case("estimate --tip-force 1e300", ["estimate", "--lab", "--tip-force", "1e300"],
             ["tip-force", "1e300"]))
    add(Case("estimate --load-step 0", ["estimate", "--lab", "--load-step", "0"],
             ["load-step", "0"]))
    add(Case("estimate --load-step 1e12", ["estimate", "--lab", "--load-step", "1e12"],
             ["load-step", "1e12|1000000000000"]))
    add(Case("estimate --load-time 0", ["estimate", "--lab", "--load-time", "0"],
             ["load-time", "0"]))
    add(Case("estimate --load-time -5", ["estimate", "--lab", "--load-time", "-5"],
             ["load-time", "-5"]))
    add(Case("estimate paper without --lab", ["estimate", "--scene", "paper"],
             ["lab|arm|loads"]))
    # ---- stability / validation / chaos / accuracy (argument checks only)
    add(Case("stability --only bogus", ["stability", "--only", "bogus", "--out", "s.md"],
             ["only", "bogus"]))
    add(Case("stability --drift-duration -1", ["stability", "--drift-duration", "-1",
                                               "--out", "s.md"], ["drift-duration", "-1"]))
    add(Case("stability --jobs 0", ["stability", "--jobs", "0", "--out", "s.md"], ["jobs", "0"]))
    add(Case("validation --converged 0", ["validation", "--converged", "0", "--out", "v.md",
                                          "--img", "img"], ["converged", "0"]))
    add(Case("validation --converged -1", ["validation", "--converged", "-1", "--out", "v.md",
                                           "--img", "img"], ["converged", "-1"]))
    add(Case("chaos --freqs -1", ["chaos", "--freqs", "-1", "--out", "c.md"], ["freqs", "-1"]))
    add(Case("chaos --steps 0", ["chaos", "--steps", "0", "--out", "c.md"], ["steps", "0"]))
    add(Case("chaos --configs bogus", ["chaos", "--configs", "bogus", "--out", "c.md"],
             ["configs", "bogus"]))
    add(Case("chaos --ensemble 0", ["chaos", "--ensemble", "0", "--out", "c.md"],
             ["ensemble", "0"]))
    add(Case("chaos --duration -1", ["chaos", "--duration", "-1", "--out", "c.md"],
             ["duration", "-1"]))
    add(Case("chaos --transient past duration", ["chaos", "--transient", "50", "--duration",
                                                 "10", "--out", "c.md"], ["transient", "50"]))
    add(Case("accuracy --repeats 0", ["accuracy", "--repeats", "0", "--out", "acc"],
             ["repeats", "0"]))
    add(Case("fmu --fmi-version 4", ["fmu", "--fmi-version", "4", "--out", "x.fmu"],
             ["fmi-version", "4"]))
    add(Case("fmu into a missing dir", ["fmu", "--fmi-version", "3", "--out", "no/such/x.fmu"],
             expect="ok"))
    add(Case("unknown command", ["bogus"], ["bogus"]))
    # ---- scene files: every section's keys with bad values, through `static` (no run).
    scene_keys = [
        ("beam", "length"), ("beam", "mass"), ("beam", "area"), ("beam", "modulus"),
        ("beam", "inertia"), ("tip", "mass"), ("tip", "inertia"), ("tip", "offset"),
        ("ball", "mass"), ("ball", "inertia"), ("ball", "radius"), ("ball", "track_radius"),
        ("ball", "stop_angle_deg"), ("ball", "restitution"), ("ball", "stick_speed"),
        ("integrator", "step"), ("integrator", "tolerance"), ("integrator", "gamma"),
        ("integrator", "beta"), ("integrator", "max_iterations"),
        ("damping", "stiffness_proportional"), ("excitation", "frequency"),
        ("excitation", "amplitude"),
    ]
    for sec, key in scene_keys:
        for v in ["nan", "-inf", "-1.0", "0.0", "1e300", "1e-300", '"abc"', "true", "[1.0]"]:
            if v in ('"abc"', "true", "[1.0]") and sec not in ("beam", "integrator"):
                continue
            text = f"[{sec}]\n{key} = {v}\n"
            exp = "error"
            # Values that are physically possible (zero offset, no damping, …): only refused
            # ones are classified.
            if v == "0.0" and (sec, key) in [("tip", "offset"), ("ball", "inertia"),
                                             ("ball", "restitution"), ("ball", "stick_speed"),
                                             ("damping", "stiffness_proportional"),
                                             ("excitation", "amplitude")]:
                exp = "any"
            if v in ("1e300", "1e-300") and (sec, key) in [("excitation", "amplitude")]:
                exp = "any"
            if v == "1e-300" and (sec, key) in [("tip", "offset"), ("ball", "inertia"),
                                                ("ball", "restitution"), ("ball", "stick_speed"),
                                                ("damping", "stiffness_proportional"),
                                                ("integrator", "tolerance")]:
                exp = "any"
            if v == "-1.0" and (sec, key) in [("tip", "offset")]:
                exp = "any"
            # Irrelevant to `static` or physically possible (a point tip, a ball that always
            # sticks, a beam damped to rest, an excitation of period 1e300 s).
            if (sec, key, v) in [("tip", "inertia", "1e-300"), ("ball", "stick_speed", "1e300"),
                                 ("damping", "stiffness_proportional", "1e300"),
                                 ("excitation", "frequency", "1e-300")]:
                exp = "any"
            vname = {"nan": "nan|NaN", "-inf": "inf", "-1.0": "-1", "0.0": "0",
                     '"abc"': "abc", "true": "true", "[1.0]": "[1.0]|array|sequence"}.get(v, v)
            add(Case(f"scene [{sec}] {key} = {v}", ["static", "--scene", "FILE:s.toml"],
                     [f"{sec}.{key}|{key}", vname], expect=exp, files={"s.toml": text}))
    for name, text, names in [
        ("scene unknown key", "[beam]\nlenght = 1.0\n", ["lenght"]),
        ("scene unknown section", "[bogus]\nx = 1\n", ["bogus"]),
        ("scene missing value", "[beam]\nlength =\n", ["length"]),
        ("scene garbage", "\x00\x01\x02 not toml", ["s.toml|line"]),
        ("scene kind bogus", 'kind = "bogus"\n', ["kind", "bogus"]),
        ("scene solver bogus", 'solver = "bogus"\n', ["solver", "bogus"]),
        ("scene precision bogus", 'precision = "f16"\n', ["precision", "f16"]),
        ("scene elements 5", "elements = 5\n", ["elements", "5"]),
        ("scene elements -1", "elements = -1\n", ["elements", "-1"]),
        ("scene elements 1.5", "elements = 1.5\n", ["elements", "1.5"]),
        ("scene duration -1", "duration = -1.0\n", ["duration", "-1"]),
        ("scene duration 1e7", "duration = 1e7\n", ["duration", "1e7|10000000"]),
        ("scene gravity nan", "gravity = nan\n", ["gravity", "nan|NaN"]),
        ("scene scheme bogus", '[integrator]\nscheme = "bogus"\n', ["scheme", "bogus"]),
        ("scene rho_inf 2", '[integrator]\nscheme = "generalized-alpha"\nrho_inf = 2.0\n',
         ["rho_inf", "2"]),
        ("scene newton bogus", '[integrator]\nnewton = "bogus"\n', ["newton", "bogus"]),
        ("scene impact bogus", '[ball]\nimpact_model = "bogus"\n', ["impact_model", "bogus"]),
        ("scene excitation type bogus", '[excitation]\ntype = "bogus"\n', ["type", "bogus"]),
        ("scene outputs every 0", "[outputs]\nevery = 0\n", ["every", "0"]),
        ("scene outputs plots bogus", '[outputs]\nplots = ["bogus"]\n', ["plots", "bogus"]),
        ("scene damping ratio -1", "[damping]\nratio = -0.1\nfrequency = 4.0\n",
         ["ratio", "-0.1"]),
        ("scene damping ratio without frequency", "[damping]\nratio = 0.01\n",
         ["frequency|ratio"]),
        ("scene ball stop angle 200 deg", "[ball]\nstop_angle_deg = 200.0\n",
         ["stop_angle_deg", "200"]),
        ("scene restitution 2", "[ball]\nrestitution = 2.0\n", ["restitution", "2"]),
        ("scene track smaller than ball", "[ball]\ntrack_radius = 0.001\nradius = 0.01\n",
         ["track_radius|radius", "0.001|0.01"]),
    ]:
        add(Case(name, ["static", "--scene", "FILE:s.toml"], names, files={"s.toml": text}))
    add(Case("scene excitation csv missing", ["run", "--scene", "FILE:s.toml"], ["none.csv"],
             files={"s.toml": '[excitation]\ntype = "csv"\nfile = "none.csv"\n'}))
    # Overrides applied before the scene is checked: a scene too long for its step is fixed
    # by `--duration`.
    add(Case("override fixes the scene", ["run", "--scene", "FILE:s.toml", "--duration", "0.2",
                                          "--no-plots"], expect="ok",
             files={"s.toml": "duration = 1e7\n"}))
    # An arm scene with bad arm keys.
    for name, old, new, names in [
        ("arm head position past the tip", "{ position = 7.0, mass = 30.0 }",
         "{ position = 70.0, mass = 30.0 }", ["heads", "70"]),
        ("arm head mass negative", "{ position = 7.0, mass = 30.0 }",
         "{ position = 7.0, mass = -30.0 }", ["heads", "-30"]),
        ("arm head mass nan", "{ position = 7.0, mass = 30.0 }",
         "{ position = 7.0, mass = nan }", ["heads", "nan|NaN"]),
        ("arm wall thicker than the tube", "wall = 0.00455", "wall = 0.5", ["wall", "0.5"]),
        ("arm detail bogus", "detail = \"E'\"", "detail = \"Q\"", ["detail", "Q"]),
        ("arm density 0", "density = 7850.0", "density = 0.0", ["density", "0"]),
    ]:
        add(Case(f"arm: {name}", ["modes", "--scene", "FILE:arm.toml"], names,
                 files={"arm.toml": ("@" + ARM_SCENE, old, new)}))
    # ---- data loss: a failed run into the directory of a good one keeps the good one.
    add(Case("data loss: failed run after a good one", ["run", "--duration", "nan", "--out",
                                                         "DIR:out"], ["duration", "nan|NaN"],
             lost=["run", "--duration", "0.2", "--no-plots", "--out", "DIR:out"]))
    add(Case("data loss: failed sweep after a good one", ["sweep", "--freqs", "nan", "--out",
                                                           "DIR:sout"], ["freqs", "nan|NaN"],
             lost=["sweep", "--freqs", "4.1", "--duration", "0.5", "--no-plots", "--out",
                   "DIR:sout"]))
    add(Case("data loss: file-size limit", ["run", "--duration", "20", "--every", "1", "--out",
                                            "DIR:fout"], ["fout"], fsize=100 * 1024,
             lost=["run", "--duration", "0.2", "--no-plots", "--out", "DIR:fout"]))
    add(Case("estimate --tip-force 10 (near resonance)", ["estimate", "--lab", "--tip-force",
                                                           "10", "--duration", "6"],
             ["tip-force", "10"], expect="any"))
    add(Case("data loss: file-size limit (sweep)", ["sweep", "--freqs", "4.1,4.13", "--duration",
                                                    "2", "--out", "DIR:fsout"], ["fsout"],
             fsize=2 * 1024,
             lost=["sweep", "--freqs", "4.1", "--duration", "0.5", "--no-plots", "--out",
                   "DIR:fsout"]))
    return c


# Python cases: (name, code, words the message must hold). The code runs after
# `import absorber`; `deep` is a dict nested 10,000 deep, `cyclic` one that holds itself.
PYTHON_PRELUDE = """
import absorber, sys
deep = {}
inner = deep
for _ in range(10_000):
    inner["x"] = {}
    inner = inner["x"]
cyclic = {"beam": {}}
cyclic["beam"]["again"] = cyclic
"""


def python_cases():
    nan = "float('nan')"
    c = [
        ("static beam.length nan", f"absorber.static({{'beam': {{'length': {nan}}}}})",
         ["beam.length", "nan|NaN"]),
        ("static beam.length -1", "absorber.static({'beam': {'length': -1.0}})",
         ["beam.length", "-1"]),
        ("static beam.length string", "absorber.static({'beam': {'length': 'abc'}})",
         ["beam.length", "abc|string"]),
        ("static unknown key", "absorber.static({'beam': {'lenght': 1.0}})", ["lenght"]),
        ("static unknown section", "absorber.static({'bogus': {}})", ["bogus"]),
        ("static key not a string", "absorber.static({1: 2})", ["key"]),
        ("static value an object", "absorber.static({'beam': {'length': object()}})",
         ["beam.length", "object"]),
        ("static scene an object", "absorber.static(object())", ["scene"]),
        ("static missing file", "absorber.static('no-such.toml')", ["no-such.toml"]),
        ("static cyclic dict", "absorber.static(cyclic)", ["beam.again", "nests deeper"]),
        ("static deep dict", "absorber.static(deep)", ["x.x", "nests deeper"]),
        ("static elements 5", "absorber.static('paper', elements=5)", ["elements", "5"]),
        ("static kind bogus", "absorber.static('paper', kind='bogus')", ["kind", "bogus"]),
        ("static override unknown", "absorber.static('paper', bogus=1)", ["bogus"]),
        ("run duration -1", "absorber.run('paper', duration=-1.0)", ["duration", "-1"]),
        ("run duration nan", f"absorber.run('paper', duration={nan})", ["duration", "nan|NaN"]),
        ("run duration string", "absorber.run('paper', duration='abc')", ["duration", "abc"]),
        ("run duration 1e300", "absorber.run('paper', duration=1e300)", ["duration", "1e300"]),
        ("run step 0", "absorber.run('paper', step=0.0)", ["step", "0"]),
        ("run frequency 1e6", "absorber.run('paper', frequency=1e6)", ["frequency", "1e6"]),
        ("run amplitude -1e-3", "absorber.run('paper', amplitude=-1e-3, duration=0.2)",
         ["amplitude", "-0.001"]),
        ("run every 0", "absorber.run('paper', every=0, duration=0.2)", ["every", "0"]),
        ("run every -1", "absorber.run('paper', every=-1, duration=0.2)", ["every", "-1"]),
        ("run ensemble 0", "absorber.run('paper', ensemble=0, duration=0.2)",
         ["ensemble", "0"]),
        ("run transient -1", "absorber.run('paper', transient=-1.0, duration=0.2)",
         ["transient", "-1"]),
        ("modes count 0", "absorber.modes('paper', count=0)", ["count", "0"]),
        ("modes count -1", "absorber.modes('paper', count=-1)", ["count", "-1"]),
        ("sweep freqs -1", "absorber.sweep('paper', freqs=[-1.0, 4.0], duration=0.5)",
         ["freq", "-1"]),
        ("sweep freqs empty", "absorber.sweep('paper', freqs=[], duration=0.5)", ["freqs"]),
        ("sweep freqs strings", "absorber.sweep('paper', freqs=['a'], duration=0.5)",
         ["freqs", "a|str"]),
        ("sweep jobs 0", "absorber.sweep('paper', freqs=[4.1], jobs=0, duration=0.5)",
         ["jobs", "0"]),
        ("sweep last -1", "absorber.sweep('paper', freqs=[4.1], last=-1.0, duration=0.5)",
         ["last", "-1"]),
    ]
    cases = [Case("python: " + n, ["PY", code], names) for n, code, names in c]
    cases.append(Case("python: sweep jobs 10**6",
                      ["PY", "absorber.sweep('paper', freqs=[4.1, 4.13], jobs=10**6, "
                             "duration=0.5)"], expect="ok"))
    return cases


NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:NaN|nan|inf)")


def holds(err, word):
    """`word` in the message, also as the same number written otherwise (1e-3 as 0.001)."""
    if word in err:
        return True
    try:
        x = float(word)
    except ValueError:
        return False
    for m in NUMBER.findall(err):
        y = float(m)
        if x == y or (x != x and y != y) or abs(x - y) <= 1e-12 * abs(x):
            return True
    return False


def materialize(case, root, repo):
    d = tempfile.mkdtemp(dir=root)
    for name, content in case.files.items():
        if isinstance(content, tuple):
            base, old, new = content
            text = open(os.path.join(repo, base[1:]), encoding="utf-8").read()
            assert old in text, (case.name, old)
            content = text.replace(old, new, 1)
        with open(os.path.join(d, name), "w", encoding="utf-8", newline="") as f:
            f.write(content)

    def arg(a):
        for prefix in ("FILE:", "DIR:"):
            if a.startswith(prefix):
                return os.path.join(d, a[len(prefix):])
        return a

    return d, arg


def digest(path):
    out = {}
    for dirpath, _, files in os.walk(path):
        for f in files:
            # The manifest records the failure (and keeps the previous run's); the lock is
            # the directory's.
            if f.endswith(".manifest.json") or f == ".host-sim.lock":
                continue
            p = os.path.join(dirpath, f)
            with open(p, "rb") as h:
                out[os.path.relpath(p, path)] = hashlib.sha256(h.read()).hexdigest()
    return out


def run_case(case, binary, root, repo):
    d, arg = materialize(case, root, repo)
    try:
        before = None
        if case.lost:
            r = subprocess.run([binary] + [arg(a) for a in case.lost], cwd=repo,
                               capture_output=True, timeout=case.timeout)
            if r.returncode != 0:
                return case, "abort", f"the good run failed: {r.stderr.decode()[-300:]}"
            before = digest(arg("DIR:" + case.lost[-1].split(":", 1)[1]))
        try:
            limit = None
            if case.fsize:
                import resource

                def limit():
                    resource.setrlimit(resource.RLIMIT_FSIZE, (case.fsize, case.fsize))
            command = [binary] + [arg(a) for a in case.args]
            if case.args[0] == "PY":
                command = [binary, "-c", PYTHON_PRELUDE + "try:\n    " + case.args[1]
                           + "\nexcept (absorber.AbsorberError, TypeError, ValueError) as e:\n"
                           "    print(f'error: {type(e).__name__}: {e}', file=sys.stderr)\n"
                           "    sys.exit(1)\n"]
            r = subprocess.run(command, cwd=d,
                               capture_output=True, timeout=case.timeout,
                               env=dict(os.environ, RUST_BACKTRACE="0"), preexec_fn=limit)
        except subprocess.TimeoutExpired:
            return case, "abort", f"no answer in {case.timeout} s (hang)"
        err = r.stderr.decode("utf-8", "replace").strip()
        rc = r.returncode
        if before is not None:
            after = digest(arg("DIR:" + case.lost[-1].split(":", 1)[1]))
            if after != before:
                changed = sorted(k for k in set(before) | set(after)
                                 if before.get(k) != after.get(k))
                return case, "lost", f"rc {rc}: outputs changed: {changed}: {err[-200:]}"
        if rc not in (0, 1, 2, 3):
            return case, "abort", f"rc {rc}: {err[-300:]}"
        if rc == 0 or rc == 3:
            if case.expect in ("ok", "any"):
                return case, "ok", ""
            return case, "wrong", f"rc {rc}, stdout: {r.stdout.decode()[:200]!r}"
        if case.expect == "ok":
            return case, "unclear", f"refused a valid input: {err[-300:]}"
        msg = err.splitlines()[-1] if err else ""
        lines = [l for l in err.splitlines() if l.startswith("error")]
        missing = [n for n in case.names
                   if not any(holds(err, alt) for alt in n.split("|"))]
        if "panicked" in err or "RUST_BACKTRACE" in err:
            return case, "abort", err[-300:]
        if missing or not ALLOWED.search(err) or (rc == 1 and len(lines) > 1):
            why = []
            if missing:
                why.append("misses " + ", ".join(missing))
            if not ALLOWED.search(err):
                why.append("says nothing of what is allowed")
            if rc == 1 and len(lines) > 1:
                why.append(f"{len(lines)} lines")
            return case, "unclear", "; ".join(why) + f": {msg[:300]}"
        return case, "clear", msg[:300]
    finally:
        shutil.rmtree(d, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(repo, "target"))
    ap.add_argument("--bin", default=os.path.join(target, "release", "host-sim"))
    ap.add_argument("--studies-bin", default=os.path.join(target, "release", "absorber-studies"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", default=None, help="cases whose name contains this")
    ap.add_argument("--max-unclear", type=int, default=0)
    ap.add_argument("--python", default=None, help="interpreter with the absorber package")
    ap.add_argument("--verbose", action="store_true", help="print every case")
    a = ap.parse_args()
    binary = os.path.abspath(a.bin)
    studies = os.path.abspath(a.studies_bin)
    root = tempfile.mkdtemp(prefix="error-matrix-")
    todo = cases() + (python_cases() if a.python else [])
    todo = [c for c in todo if a.only is None or a.only in c.name]

    def run(c):
        if c.args[0] == "PY":
            tool = a.python
        elif c.args[0] in ("stability", "accuracy", "validation", "chaos"):
            tool = studies
        else:
            tool = binary
        return run_case(c, tool, root, repo)
    counts = {}
    try:
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
            results = list(ex.map(run, todo))
    finally:
        shutil.rmtree(root, ignore_errors=True)
    for case, kind, detail in results:
        counts[kind] = counts.get(kind, 0) + 1
        if a.verbose or kind not in ("clear", "ok"):
            print(f"{kind:8} {case.name}: {detail}")
    order = ["clear", "ok", "unclear", "wrong", "abort", "lost"]
    print(f"{len(results)} cases: " + ", ".join(f"{k} {counts.get(k, 0)}" for k in order))
    bad = sum(counts.get(k, 0) for k in ("wrong", "abort", "lost"))
    sys.exit(1 if bad or counts.get("unclear", 0) > a.max_unclear else 0)


if __name__ == "__main__":
    main()
