#!/usr/bin/env python3
"""Where a firmware's guest instructions go, per function, under QEMU.

Runs ELF on QEMU's netduinoplus2 (STM32F405) with `-d in_asm,exec,nochain` (every
translated block's instructions and every execution of a block are logged), then charges
each executed block's instructions to the function containing its start address
(arm-none-eabi-nm). With --between START END (symbol names of two #[inline(never)]
functions the firmware calls around the code of interest), only blocks executed between
the first call of START and the next call of END are counted.

  scripts/qemu-profile.py ELF [--between START END] [--top N] [--callers SYMBOL]...
                          [--timeout SECONDS]

Exact for straight-line blocks; a block left early by an exception is still charged whole
(rare in these benchmarks). Counts are guest instructions, the same unit as the
benchmarks'.
"""
import argparse
import bisect
import collections
import re
import subprocess
import sys
import tempfile


def symbols(elf):
    out = subprocess.run(["arm-none-eabi-nm", "-C", "-n", "-S", elf],
                         capture_output=True, text=True, check=True).stdout
    syms = []
    for line in out.splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in "tTwW":
            syms.append((int(parts[0], 16) & ~1, int(parts[1], 16), parts[3]))
    syms.sort()
    return syms


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("elf")
    ap.add_argument("--between", nargs=2, metavar=("START", "END"))
    ap.add_argument("--top", type=int, default=30)
    ap.add_argument("--timeout", type=int, default=600)
    ap.add_argument("--callers", metavar="SYMBOL", action="append", default=[],
                    help="also list who enters SYMBOL (the block run just before its first), and how often")
    a = ap.parse_args()

    syms = symbols(a.elf)
    starts = [s[0] for s in syms]

    def owner(pc):
        i = bisect.bisect_right(starts, pc) - 1
        if i >= 0 and pc < syms[i][0] + max(syms[i][1], 2):
            return syms[i][2]
        return "?"

    marks = {}
    if a.between:
        for name in a.between:
            hits = [s[0] for s in syms if s[2] == name]
            if not hits:
                sys.exit(f"--between: symbol {name!r} not found in {a.elf}")
            marks[name] = hits[0]

    with tempfile.NamedTemporaryFile(suffix=".log") as log:
        run = subprocess.run(["timeout", str(a.timeout), "qemu-system-arm", "-cpu", "cortex-m4",
                              "-machine", "netduinoplus2", "-nographic", "-icount", "shift=0",
                              "-semihosting-config", "enable=on,target=native",
                              "-d", "in_asm,exec,nochain", "-D", log.name, "-kernel", a.elf],
                             stdout=subprocess.DEVNULL, check=False)
        # 0 or 1 is the firmware's own verdict (a benchmark over its budget still ran to
        # its end); anything else (124: the timeout) leaves a partial log.
        if run.returncode not in (0, 1):
            why = f" (timed out after {a.timeout} s)" if run.returncode == 124 else ""
            sys.exit(f"qemu-profile: QEMU ended with status {run.returncode}{why}: "
                     "the log is partial, no profile given")
        size = {}  # block start pc -> instructions
        per_fn = collections.Counter()
        total = 0
        state = "before" if a.between else "in"
        cur_tb = None
        prev_pc = None
        entries = {name: collections.Counter() for name in a.callers}
        entry_pc = {}
        for name in a.callers:
            hits = [x[0] for x in syms if x[2] == name]
            if not hits:
                sys.exit(f"--callers: symbol {name!r} not found in {a.elf}")
            entry_pc[hits[0]] = name
        tb_re = re.compile(r"^Trace \d+: \S+ \[[0-9a-f]+/([0-9a-f]+)/")
        with open(log.name, errors="replace") as f:
            for line in f:
                if line.startswith("IN:"):
                    cur_tb = None
                    continue
                if line.startswith("0x") and ":" in line:
                    pc = int(line.split(":", 1)[0], 16)
                    if cur_tb is None:
                        cur_tb = pc
                        size[pc] = 0
                    size[cur_tb] += 1
                    continue
                m = tb_re.match(line)
                if not m:
                    cur_tb = None if not line.strip() else cur_tb
                    continue
                pc = int(m.group(1), 16)
                if a.between:
                    if state == "before" and pc == marks[a.between[0]]:
                        state = "in"
                        continue
                    if state == "in" and pc == marks[a.between[1]]:
                        break
                if state != "in":
                    continue
                n = size.get(pc, 0)
                if pc in entry_pc and prev_pc is not None:
                    entries[entry_pc[pc]][owner(prev_pc)] += 1
                prev_pc = pc
                per_fn[owner(pc)] += n
                total += n
    print(f"{total} guest instructions counted")
    for name, n in per_fn.most_common(a.top):
        print(f"{n:10d} {100.0 * n / max(total, 1):5.1f}%  {name[:150]}")
    for target, callers in entries.items():
        print(f"\nentries into {target}:")
        for name, n in callers.most_common(a.top):
            print(f"{n:10d}  from {name[:150]}")


if __name__ == "__main__":
    main()
