# SPDX-License-Identifier: GPL-3.0-or-later
"""What a .blend's bytes are: its blocks summed by the struct they hold, read from the file
itself (its block headers and its own struct catalogue, SDNA), so a file's growth can be
split into sampled frames, keys, F-curves and the rest.

Reads the block format Blender 4.x writes uncompressed (``BLENDER`` + pointer size +
endianness + version); a compressed file, or the format of 5.0 and later, is refused with
ValueError. No Blender needed:

    python bench/blend_blocks.py before.blend after.blend
"""

import struct
import sys
from collections import Counter

# What a block's struct is to a reader of the growth table
KINDS = {
    "FPoint": "sampled frames (FPoint, 16 bytes a frame)",
    "BezTriple": "keys (BezTriple, 72 bytes a key)",
    "FCurve": "F-curves",
    "bActionGroup": "bone groups of actions",
    "raw_data": "strings and arrays (paths, plan records)",
    "IDProperty": "custom properties",
    "NlaStrip": "NLA strips and tracks",
    "NlaTrack": "NLA strips and tracks",
    "FModifier": "F-curve modifiers (a loop's cycles)",
    "FMod_Cycles": "F-curve modifiers (a loop's cycles)",
}


def _cstrings(data, at, count):
    out = []
    for _ in range(count):
        end = data.index(b"\0", at)
        out.append(data[at:end].decode("latin-1"))
        at = end + 1
    return out, (at + 3) & ~3


def _struct_names(sdna):
    """The struct type name of each SDNA struct index, from the DNA1 block's payload."""
    at = 8  # "SDNA" "NAME"
    (n,) = struct.unpack_from("<i", sdna, at)
    _, at = _cstrings(sdna, at + 4, n)
    if sdna[at : at + 4] != b"TYPE":
        raise ValueError("no TYPE section in the file's SDNA")
    (n,) = struct.unpack_from("<i", sdna, at + 4)
    types, at = _cstrings(sdna, at + 8, n)
    if sdna[at : at + 4] != b"TLEN":
        raise ValueError("no TLEN section in the file's SDNA")
    at = (at + 4 + 2 * n + 3) & ~3
    if sdna[at : at + 4] != b"STRC":
        raise ValueError("no STRC section in the file's SDNA")
    (n,) = struct.unpack_from("<i", sdna, at + 4)
    at += 8
    names = []
    for _ in range(n):
        t, fields = struct.unpack_from("<hh", sdna, at)
        names.append(types[t])
        at += 4 + 4 * fields
    return names


def block_bytes(path):
    """{struct name: bytes its blocks take in the file, headers included}."""
    data = open(path, "rb").read()
    if data[:7] != b"BLENDER" or data[7:8] not in (b"-", b"_") or data[8:9] != b"v":
        raise ValueError(
            f"{path}: not a .blend in Blender 4.x's uncompressed format (saved compressed, "
            "or by Blender 5.0 or later)"
        )
    ptr = 8 if data[7:8] == b"-" else 4
    head = 16 + ptr
    at, blocks, sdna = 12, [], None
    while at + head <= len(data):
        code = data[at : at + 4]
        (length,) = struct.unpack_from("<i", data, at + 4)
        (index,) = struct.unpack_from("<i", data, at + 8 + ptr)
        if code == b"DNA1":
            sdna = data[at + head : at + head + length]
        blocks.append((index, length + head))
        if code == b"ENDB":
            break
        at += head + length
    if sdna is None:
        raise ValueError(f"{path}: no struct catalogue (DNA1 block)")
    names = _struct_names(sdna)
    out = Counter()
    for index, size in blocks:
        out[names[index] if 0 <= index < len(names) else "?"] += size
    return out


def growth(before, after):
    """[(kind, bytes)] the file grew by from ``before`` to ``after``, largest first, kinds
    as :data:`KINDS` names them (everything else together as "other")."""
    a, b = block_bytes(before), block_bytes(after)
    by_kind = Counter()
    for name in set(a) | set(b):
        by_kind[KINDS.get(name, "other")] += b[name] - a[name]
    return sorted(by_kind.items(), key=lambda kv: -kv[1])


if __name__ == "__main__":
    for kind, size in growth(sys.argv[1], sys.argv[2]):
        print(f"{size / 1024:9.1f} KB  {kind}")
