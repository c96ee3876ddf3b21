#!/usr/bin/env python3
"""Lists the panic paths of the library crates left in firmware ELFs, and fails on any.

A panic the compiler cannot rule out (a slice copy whose lengths it cannot prove equal, an
index it cannot prove in bounds) keeps a `core::panic::Location` in the image: the source
file's path, its length, the line and the column, in `.rodata`. The libraries deny
`unwrap`, `expect`, `panic!` and indexing, but not these; this check finds them in what the
firmware really links. A location is the library's when its path is under ROOT's `src/`,
`idu-gimbal-mavlink/src/` or `idu-gimbal-fdcan/src/` (cargo names a path dependency outside
the building workspace by its absolute path, as the board crates see the libraries).

Only a panic handler that reads the location keeps them (panic-probe, defmt), so an ELF
with no location at all is an error too: the check would prove nothing there.

    scripts/panic-paths.py ROOT ELF...
    scripts/panic-paths.py --self-test   the search on made-up `.rodata`

Exit 0: no library location in any ELF; 1: some (listed), or an ELF without locations;
2: bad usage. Reads the ELFs with pyelftools (scripts/firmware-env.sh installs it).
"""

import re
import struct
import sys

from elftools.common.exceptions import ELFError
from elftools.elf.elffile import ELFFile

LIBRARY_SOURCES = ("src/", "idu-gimbal-mavlink/src/", "idu-gimbal-fdcan/src/")


def rodata(path):
    """The `.rodata` section of a 32-bit little-endian ELF: (address, bytes)."""
    with open(path, "rb") as f:
        elf = ELFFile(f)
        if elf.elfclass != 32 or not elf.little_endian:
            raise ValueError(f"{path}: not a 32-bit little-endian ELF")
        section = elf.get_section_by_name(".rodata")
        if section is None:
            raise ValueError(f"{path}: no .rodata section")
        return section["sh_addr"], section.data()


# A source path as a `Location` names it: printable, no NUL or control bytes (spaces are
# allowed: a checkout's path may hold them), ending in `.rs`.
SOURCE_PATH = re.compile(rb"[^\x00-\x1f\x7f]+\.rs")


def locations(path):
    """Every (file, line, column) a `Location` in the ELF's `.rodata` names.

    A `Location` is four aligned words: a pointer to its file's path, the path's length,
    the line and the column. Every aligned place in `.rodata` is read as one, and kept when
    its pointer and length name a source path inside `.rodata`: the paths themselves are
    packed with other strings, with nothing between them, so they are found through the
    records that point at them rather than by searching the bytes for paths.
    """
    addr, data = rodata(path)
    found = set()
    for at in range(-addr % 4, len(data) - 15, 4):
        pointer, length, line, column = struct.unpack_from("<IIII", data, at)
        start = pointer - addr
        if not (0 <= start and 3 < length <= 4096 and start + length <= len(data)):
            continue
        if not (0 < line < 1_000_000 and column < 1_000_000):
            continue
        name = data[start:start + length]
        if SOURCE_PATH.fullmatch(name):
            found.add((name.decode("utf-8", "replace"), line, column))
    return sorted(found)


def self_test():
    """The search on made-up `.rodata`: a path packed right after other text, one with a
    space, and a path with no `Location` pointing at it. Returns the failures."""
    addr = 0x0800_1000
    text = b"out of rangesrc/link/mod.rs/my work/src/geo.rsunused/x.rs"
    blob = text + b"\0" * (-len(text) % 4) + struct.pack("<IIII", addr + 12, 15, 42, 7)
    blob += struct.pack("<IIII", addr + 27, 19, 310, 9)
    want = [("/my work/src/geo.rs", 310, 9), ("src/link/mod.rs", 42, 7)]
    global rodata
    real, rodata = rodata, lambda _path: (addr, blob)
    try:
        got = locations("self-test")
    finally:
        rodata = real
    return [] if got == want else [f"found {got}, expected {want}"]


def main(argv):
    if argv[1:] == ["--self-test"]:
        failures = self_test()
        for f in failures:
            print(f"panic-paths: self-test: {f}", file=sys.stderr)
        print("panic-paths: self-test " + ("failed" if failures else "passed"))
        return 1 if failures else 0
    if len(argv) < 3:
        print("usage: panic-paths.py ROOT ELF... (ROOT: the repository's root directory) "
              "or panic-paths.py --self-test", file=sys.stderr)
        return 2
    root = argv[1].rstrip("/") + "/"
    library = tuple(root + s for s in LIBRARY_SOURCES)
    failed = False
    for elf in argv[2:]:
        try:
            found = locations(elf)
        except ELFError as e:
            print(f"panic-paths: {elf}: not an ELF the check can read: {e}", file=sys.stderr)
            return 1
        except (OSError, ValueError) as e:
            print(f"panic-paths: {e}", file=sys.stderr)
            return 1
        ours = [loc for loc in found if loc[0].startswith(library)]
        if not found:
            print(f"{elf}: no panic location at all: its panic handler drops them, so this "
                  "check proves nothing here")
            failed = True
        elif ours:
            failed = True
            print(f"{elf}: {len(ours)} panic path(s) in the libraries:")
            for name, line, column in ours:
                print(f"  {name[len(root):]}:{line}:{column}")
        else:
            print(f"{elf}: {len(found)} panic locations, none in the libraries")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
