#!/usr/bin/env python3
"""Checks measured embedded figures (the JSON embedded-report.py writes) against
firmware/budget.toml. Prints one line per scene and figure; exits 1 if any figure exceeds its
budget, a budgeted scene is missing, a stack bound could not be established, a step of any run
exceeds its bin's static work bound, a panic path or an indirect call is reachable from `step`,
the planted panic of `fw-planted` is not found, or a stress run is not bit-identical to the host.
Usage: embedded-budget.py <figures.json> [firmware/budget.toml]"""

import json
import sys
import tomllib
from pathlib import Path

figures = json.loads(Path(sys.argv[1]).read_text())
budget_path = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).resolve().parent.parent / "firmware" / "budget.toml"
budget = tomllib.loads(budget_path.read_text())
failed = []
if not figures.get("planted_panic", {}).get("found"):
    failed.append("fw-planted: the panic planted on its step path was not found (the check proves nothing)")
for key, f in figures.items():
    if key.startswith("stress_") and not f["bit_identical"]:
        failed.append(f"{key}: QEMU run differs from the host")
for key, b in budget.items():
    f = figures.get(key)
    if f is None:
        failed.append(f"{key}: not measured")
        continue
    checks = []
    if key.startswith("stress_"):
        of = figures[f["of"]]
        if "worst_over_mean" in b:
            checks.append(("worst / bin's mean", round(f["worst"] / of["mean"], 3), b["worst_over_mean"]))
        for k, name in (("worst", "worst instructions/step"), ("error_steps", "error steps")):
            if k in b:
                checks.append((name, f[k], b[k]))
    else:
        for k, name in (("mean", "mean instructions/step"), ("worst", "worst instructions/step"),
                        ("work_bound", "static work bound"), ("boot_ram", "boot RAM [B]"),
                        ("error_steps", "error steps (paper)"), ("flash_opt3", "flash opt 3 [B]"),
                        ("flash_opt_s", "flash opt s [B]")):
            if k in b:
                checks.append((name, f[k], b[k]))
        if "work_bound_over_mean" in b:
            checks.append(("work bound / mean", round(f["work_bound"] / f["mean"], 3), b["work_bound_over_mean"]))
        # The bound is a bound: no step of any run (paper and stress) may exceed it.
        checks.append(("worst of all runs vs bound", f["worst_with_stress"], f["work_bound"]))
        if "stack_bound" in b:
            if f["stack_bound"] is None:
                failed.append(f"{key}: no static stack bound ({f['deepest_chain']})")
            else:
                checks.append(("stack bound [B]", f["stack_bound"], b["stack_bound"]))
        # No bin may reach a panic from its step (no allowance: the house rule).
        if f.get("panic_paths_from_step", 0) > 0:
            failed.append(f"{key}: {f['panic_paths_from_step']} panic path(s) reachable from step")
        if f.get("indirect_calls_from_step", 0):
            failed.append(f"{key}: {f['indirect_calls_from_step']} indirect call(s) reachable from step")
    for name, value, limit in checks:
        ok = value <= limit
        print(f"budget {key:32} {name:28} {value:>12,} {'<=' if ok else '>'} {limit:,}")
        if not ok:
            failed.append(f"{key}: {name} {value:,} exceeds {limit:,}")
for line in failed:
    print(f"BUDGET EXCEEDED: {line}")
sys.exit(1 if failed else 0)
