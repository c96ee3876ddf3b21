#!/usr/bin/env python3
"""Side by side: the result tables of two `scripts/bench.sh` outputs.

Usage: bench-compare.py OTHER.txt THIS.txt OTHER_NAME THIS_NAME

Every Markdown table row with a number in its second cell is a measurement, named by its
first cell (prefixed with its table's name when that table is not the guest-instruction
table, so that the size tables' "flash" rows stay apart); in a table of two measured
columns (the C library beside the bridge) each column is a measurement of its own, named
with its header. Rows appear in THIS's order, then
those only OTHER has; a missing number shows as "-".
"""
import re
import sys

NUMBER = re.compile(r"^-?[0-9][0-9.,]*")


# Header cells of columns that are not measurements.
NOT_MEASURED = {"budget", "verdict", "margin", ""}


def rows(path):
    out = {}
    table = ""
    # The measured columns after the first, as (index, header), of the table being read: a
    # comparison table (`| measurement | C MAVLink library | bridge | budget | verdict |`)
    # has two, each kept apart as "name (header)".
    measured = [(1, "")]
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            line = line.strip()
            if not line.startswith("|"):
                continue
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) < 2 or set(cells[1]) <= set("-: "):
                continue
            if not NUMBER.match(cells[1]):
                # A header row: its first cell names the table.
                table = "" if cells[0].startswith("measurement") else cells[0]
                heads = [(i, c) for i, c in enumerate(cells) if i >= 1 and c.lower() not in NOT_MEASURED]
                measured = heads if len(heads) > 1 else [(1, "")]
                continue
            base = f"{table}: {cells[0]}" if table else cells[0]
            for i, head in measured:
                m = NUMBER.match(cells[i]) if i < len(cells) else None
                if not m:
                    continue
                name = f"{base} ({head})" if head else base
                # A unit follows the number; a ratio in parentheses is not one.
                unit = cells[i][m.end():].split("(")[0].strip()
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
