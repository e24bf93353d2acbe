"""Checks of the data-parallel MPI mode, with the standard library only.

  mpi_checks.py diff A.pfm B.pfm MAX MEAN ABOVE
      the float images differ by at most MAX per channel, MEAN on average, and at most a share
      ABOVE of the channels differ by more than 2/255 (MAX < 0: not checked)
  mpi_checks.py parts INFO.json NAME.cells
      `info --json` under MPI: the parts tile the lattice, every cell is owned by one part, and
      each part's resident cells are exactly those whose basis support reaches into its box
      grown by two coarsest cell widths
"""
import json
import struct
import sys


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        channels = 3 if kind == b"PF" else 1
        count = width * height * channels
        data = struct.unpack(("<" if scale < 0 else ">") + "%df" % count, f.read(4 * count))
    return width, height, data


def diff(a, b, max_allowed, mean_allowed, above_allowed):
    wa, ha, da = read_pfm(a)
    wb, hb, db = read_pfm(b)
    if (wa, ha) != (wb, hb):
        print(f"sizes differ: {wa}x{ha} and {wb}x{hb}")
        return 1
    diffs = [abs(x - y) for x, y in zip(da, db)]
    largest = max(diffs)
    mean = sum(diffs) / len(diffs)
    above = sum(1 for d in diffs if d > 2 / 255) / len(diffs)
    print(f"max {largest * 255:.2f}/255, mean {mean * 255:.4f}/255, {above * 100:.3f} % of channels above 2/255")
    ok = mean <= mean_allowed and above <= above_allowed and (max_allowed < 0 or largest <= max_allowed)
    return 0 if ok else 1


def parts(info_path, cells_path):
    info = json.load(open(info_path))
    with open(cells_path, "rb") as f:
        raw = f.read()
    cells = [struct.unpack_from("<4i", raw, 16 * i) for i in range(len(raw) // 16)]
    big = 1 << 60

    def box(rank):
        lo = [big * -1 if v is None else v for v in rank["box"]["lower"]]
        hi = [big if v is None else v for v in rank["box"]["upper"]]
        return lo, hi

    # A part holds the cells whose support reaches its box grown by two coarsest cell widths
    # (smooth shading's gradients difference the field one cell beyond a resident cell).
    reach = 2 << max((c[3] for c in cells), default=0)
    boxes = [box(r) for r in info["ranks"]]
    failures = 0
    owned = [0] * len(boxes)
    resident = [0] * len(boxes)
    for x, y, z, level in cells:
        w = 1 << level
        c = (x, y, z)
        owners = 0
        for k, (lo, hi) in enumerate(boxes):
            if all(2 * lo[a] <= 2 * c[a] + w < 2 * hi[a] for a in range(3)):
                owners += 1
                owned[k] += 1
            # The support is the open interval (c + w/2 - w, c + w/2 + w) per axis.
            if all(2 * c[a] - w < 2 * (hi[a] + reach) and 2 * c[a] + 3 * w > 2 * (lo[a] - reach) for a in range(3)):
                resident[k] += 1
        if owners != 1:
            failures += 1
    if failures:
        print(f"{failures} cells are not owned by exactly one part")
    if info["cells"] != len(cells):
        print(f"info reports {info['cells']} cells, the file holds {len(cells)}")
        failures += 1
    for k, r in enumerate(info["ranks"]):
        if r["owned_cells"] != owned[k] or r["resident_cells"] != resident[k]:
            print(f"rank {k}: reports {r['owned_cells']} owned / {r['resident_cells']} resident, "
                  f"expected {owned[k]} / {resident[k]}")
            failures += 1
        if r["halo_cells"] != r["resident_cells"] - r["owned_cells"]:
            failures += 1
    mean = len(cells) / len(boxes)
    print("owned per part:", owned, "resident:", resident)
    if max(owned) > 1.25 * mean:
        print(f"unbalanced: {max(owned)} cells in one part, mean {mean:.0f}")
        failures += 1
    return 1 if failures else 0


if __name__ == "__main__":
    if sys.argv[1] == "diff":
        sys.exit(diff(sys.argv[2], sys.argv[3], *map(float, sys.argv[4:7])))
    if sys.argv[1] == "parts":
        sys.exit(parts(sys.argv[2], sys.argv[3]))
    sys.exit(f"unknown check {sys.argv[1]}")
