#!/usr/bin/env python3
"""Checks measured embedded figures (the JSON embedded-report.py writes) against
firmware/budget.toml. Prints one line per scene and figure; exits 1 if any figure exceeds its
budget, a budgeted scene is missing, a stack bound could not be established, or a panic path is
reachable from `step`. Usage: embedded-budget.py <figures.json> [firmware/budget.toml]"""

import json
import sys
import tomllib
from pathlib import Path

figures = json.loads(Path(sys.argv[1]).read_text())
budget_path = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).resolve().parent.parent / "firmware" / "budget.toml"
budget = tomllib.loads(budget_path.read_text())
failed = []
for key, b in budget.items():
    f = figures.get(key)
    if f is None:
        failed.append(f"{key}: not measured")
        continue
    checks = []
    if "mean" in b:
        checks.append(("mean instructions/step", f["mean"], b["mean"]))
    if "worst" in b:
        checks.append(("worst instructions/step", f["worst"], b["worst"]))
    if "worst_over_mean" in b:
        checks.append(("worst/mean", round(f["worst"] / f["mean"], 3), b["worst_over_mean"]))
    if "stack_bound" in b:
        if f["stack_bound"] is None:
            failed.append(f"{key}: no static stack bound ({f['deepest_chain']})")
        else:
            checks.append(("stack bound [B]", f["stack_bound"], b["stack_bound"]))
    for k, name in (("flash_opt3", "flash opt 3 [B]"), ("flash_opt_s", "flash opt s [B]")):
        if k in b:
            checks.append((name, f[k], b[k]))
    if f.get("panic_paths_from_step", 0):
        failed.append(f"{key}: {f['panic_paths_from_step']} panic path(s) reachable from step")
    for name, value, limit in checks:
        ok = value <= limit
        print(f"budget {key:22} {name:26} {value:>12,} {'<=' if ok else '>'} {limit:,}")
        if not ok:
            failed.append(f"{key}: {name} {value:,} exceeds {limit:,}")
for line in failed:
    print(f"BUDGET EXCEEDED: {line}")
sys.exit(1 if failed else 0)
