#!/usr/bin/env python3
"""Writes random inputs for the `step` fuzz target: one byte of parameter mask (half of them 0:
Table 1), a factor per set bit, then 400 base accelerations (f32, uniform in ±A with A drawn
from 1 m/s² to 9,000 m/s², a NaN, an infinity or an out-of-range spike in one input of ten).
Uninstrumented libFuzzer keeps no corpus, so these are run as a fixed set (`step DIR/*`): every
input is 400 model steps, 25,000 inputs 10⁷ steps.
Usage: gen-step-inputs.py <dir> [count] [seed]"""

import random
import struct
import sys
from pathlib import Path

out = Path(sys.argv[1])
count = int(sys.argv[2]) if len(sys.argv) > 2 else 25000
rng = random.Random(int(sys.argv[3]) if len(sys.argv) > 3 else 1)
out.mkdir(parents=True, exist_ok=True)
for i in range(count):
    mask = 0 if i % 2 == 0 else rng.randrange(256)
    data = bytes([mask])
    for _ in range(bin(mask).count("1")):
        data += struct.pack("<f", rng.choice([rng.uniform(0.3, 3.0), rng.uniform(1e-3, 1e3)]))
    amp = rng.choice([1.0, 10.0, 50.0, 200.0, 2000.0, 9000.0])
    vals = [rng.uniform(-amp, amp) for _ in range(400)]
    if rng.random() < 0.1:
        vals[rng.randrange(400)] = rng.choice([float("nan"), float("inf"), 1e6, -3e4])
    data += b"".join(struct.pack("<f", v) for v in vals)
    (out / f"in{i:05d}").write_bytes(data)
