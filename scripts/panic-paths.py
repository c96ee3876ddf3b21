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


def locations(path):
    """Every (file, line, column) a `Location` in the ELF's `.rodata` names."""
    addr, data = rodata(path)
    found = set()
    for m in re.finditer(rb"[\w\-./]+\.rs", data):
        pointer = struct.pack("<I", addr + m.start())
        for at in (p.start() for p in re.finditer(re.escape(pointer), data)):
            if at % 4 or at + 16 > len(data):
                continue
            _, length, line, column = struct.unpack_from("<IIII", data, at)
            if 0 < length <= len(m.group(0)) and 0 < line < 1_000_000:
                name = data[m.start():m.start() + length].decode("utf-8", "replace")
                found.add((name, line, column))
    return sorted(found)


def main(argv):
    if len(argv) < 3:
        print("usage: panic-paths.py ROOT ELF... (ROOT: the repository's root directory)",
              file=sys.stderr)
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
