"""Writes NAME.cells / NAME.scalars: a two-level dataset whose refined block and whose hole (a box
without cells) straddle the middle planes, where a k-d split into parts falls. Used by the
data-parallel MPI checks."""
import math
import struct
import sys


def main(path):
    cells, values = [], []

    def value(x, y, z):
        return math.sin(0.21 * x) * math.cos(0.17 * y) + 0.02 * z

    def inside(p, lo, hi):
        return all(lo[a] <= p[a] < hi[a] for a in range(3))

    fine_lo, fine_hi = (20, 16, 12), (44, 40, 36)    # level 0 (width 1) here
    hole_lo, hole_hi = (24, 26, 36), (40, 38, 56)    # no cells here (corners aligned to 2)
    for z in range(0, 64, 2):
        for y in range(0, 64, 2):
            for x in range(0, 64, 2):
                if inside((x, y, z), hole_lo, hole_hi):
                    continue
                if inside((x, y, z), fine_lo, fine_hi):
                    for dz in (0, 1):
                        for dy in (0, 1):
                            for dx in (0, 1):
                                p = (x + dx, y + dy, z + dz)
                                cells.append(struct.pack("<4i", *p, 0))
                                values.append(value(p[0] + 0.5, p[1] + 0.5, p[2] + 0.5))
                else:
                    cells.append(struct.pack("<4i", x, y, z, 1))
                    values.append(value(x + 1.0, y + 1.0, z + 1.0))
    stem = path[: -len(".cells")]
    with open(path, "wb") as f:
        f.write(b"".join(cells))
    with open(stem + ".scalars", "wb") as f:
        f.write(struct.pack("<%df" % len(values), *values))


if __name__ == "__main__":
    main(sys.argv[1])
