#!/usr/bin/env python3
"""Side by side: the result tables of two `scripts/bench.sh` outputs.

Usage: bench-compare.py OTHER.txt THIS.txt OTHER_NAME THIS_NAME

Every Markdown table row with a number in its second cell is a measurement, named by its
first cell (prefixed with its table's name when that table is not the guest-instruction
table, so that the size tables' "flash" rows stay apart). Rows appear in THIS's order, then
those only OTHER has; a missing number shows as "-".
"""
import re
import sys

NUMBER = re.compile(r"^-?[0-9][0-9.,]*")


def rows(path):
    out = {}
    table = ""
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            line = line.strip()
            if not line.startswith("|"):
                continue
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) < 2 or set(cells[1]) <= set("-: "):
                continue
            m = NUMBER.match(cells[1])
            if not m:
                # A header row: its first cell names the table.
                table = "" if cells[0] == "measurement" else cells[0]
                continue
            name = f"{table}: {cells[0]}" if table else cells[0]
            unit = cells[1][m.end():].strip()
            out.setdefault(name, (m.group(0).replace(",", ""), unit))
    return out


def main():
    if len(sys.argv) != 5:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    other, this = rows(sys.argv[1]), rows(sys.argv[2])
    if not other:
        print(f"warning: no results from {sys.argv[3]} (its build or run failed?)", file=sys.stderr)
    names = list(this) + [n for n in other if n not in this]
    print(f"| measurement | {sys.argv[3]} | {sys.argv[4]} | change |")
    print("|---|---:|---:|---:|")
    for n in names:
        a = other.get(n, ("-", ""))
        b = this.get(n, ("-", ""))
        unit = b[1] or a[1]
        change = ""
        try:
            x, y = float(a[0]), float(b[0])
            change = f"{y - x:+.1f}" + (f" ({(y - x) / x * 100:+.1f} %)" if x else "")
        except ValueError:
            pass
        print(f"| {n} | {a[0]} {unit} | {b[0]} {unit} | {change} |".replace("  |", " |"))


main()
