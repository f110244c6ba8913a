#!/usr/bin/env python3
"""Where a firmware step's instructions go, from the QEMU plugin's block profile.

    python3 scripts/embedded-profile.py <stem> <elf> [part ...]

<stem>.prof (`<pc> <instructions in the block> <instructions executed in it>`, written by
scripts/qemu-step-counter.c with `prof=`) and <stem>.counts (one line per counted call) are what
scripts/embedded-report.sh leaves in the target directory (`embedded-report/fw-<scene>`), <elf>
the firmware it ran (built with debug line tables: the `fw` profile). Each block is attributed
through its inline chain (`arm-none-eabi-addr2line -i`) to the innermost of the given parts
(function names, the last path segment: `propagate`, `directions`, …) that the chain holds, else
to the block's symbol (a part given by the symbol's name also matches there). A function that is
not inlined counts as itself whoever calls it. Prints instructions per counted call (exact: the profile's sums
over the run divided by the calls), largest first.

Example (the monitor loop's filter):
    python3 scripts/embedded-profile.py target/embedded-report/fw-monitor-loop \\
        target/thumbv7em-none-eabihf/fw/fw-monitor-loop step_with_loads monitor_record \\
        residual_and_jacobian solve directions propagate thornton measurement_rows apply
"""

import bisect
import collections
import subprocess
import sys


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    stem, elf, parts = sys.argv[1], sys.argv[2], sys.argv[3:]
    calls = sum(1 for _ in open(stem + ".counts"))
    prof = [line.split() for line in open(stem + ".prof")]
    text = "\n".join(p[0] for p in prof) + "\n"
    out = subprocess.run(["arm-none-eabi-addr2line", "-f", "-i", "-C", "-a", "-e", elf],
                         input=text, capture_output=True, text=True, check=True).stdout.splitlines()
    chains, pc, i = {}, None, 0
    while i < len(out):
        if out[i].startswith("0x"):
            pc = int(out[i], 16)
            chains[pc] = []
            i += 1
        else:
            chains[pc].append(out[i])
            i += 2
    nm = subprocess.run(["arm-none-eabi-nm", "-C", elf], capture_output=True, text=True,
                        check=True).stdout.splitlines()
    syms = sorted((int(f[0], 16) & ~1, f[2]) for f in (l.split(None, 2) for l in nm)
                  if len(f) == 3 and f[1] in "tTwW")
    starts = [a for a, _ in syms]
    total = collections.Counter()
    for pc_hex, _, executed in prof:
        pc = int(pc_hex, 16)
        k = bisect.bisect_right(starts, pc) - 1
        symbol = syms[k][1] if k >= 0 else "?"
        # Innermost first: the most specific part that holds the block's code.
        frames = chains.get(pc, []) + [symbol]
        key = next((p for f in frames for p in parts if f.endswith("::" + p) or f == p), symbol)
        total[key] += int(executed)
    print(f"{sum(total.values()) / calls:10.0f}  instructions per call ({calls} calls)")
    for key, n in total.most_common():
        if n / calls >= 1:
            print(f"{n / calls:10.0f}  {key}")


if __name__ == "__main__":
    main()
