"""A small Enzo output (parameter file, hierarchy, one packed HDF5 file) that both yt and
exabricks read: a root grid of 8^3 cells over [0, 1]^3 and one level-1 grid of 8^3 cells over
[0.25, 0.75]^3; fields Density (code units: 1 + a peak of 100 at the centre) and Temperature
(10^4 times Density); DensityUnits 1e-27 g/cm^3."""
import os

import numpy as np

DENSITY_UNITS = 1e-27

_PARAMETERS = """InitialCycleNumber = 3
InitialTime = 0.5
VersionNumber = 2.0
CosmologyCurrentRedshift = 2.5
ComovingCoordinates = 0
TopGridRank = 3
TopGridDimensions = 8 8 8
RefineBy = 2
MaximumRefinementLevel = 1
DomainLeftEdge = 0 0 0
DomainRightEdge = 1 1 1
LeftFaceBoundaryCondition = 3 3 3
RightFaceBoundaryCondition = 3 3 3
LengthUnits = 3.0857e+24
DensityUnits = {density_units}
TimeUnits = 3.15576e+16
HydroMethod = 0
DualEnergyFormalism = 0
MultiSpecies = 0
SelfGravity = 0
NumberOfParticles = 0
CurrentTimeIdentifier = 0
DataLabel[0] = Density
DataLabel[1] = Temperature
Gamma = 1.6667
"""

_GRIDS = [(1, 0, 0.0, 1.0), (2, 1, 0.25, 0.75)]  # id, level, left, right (the same on every axis)


def density(x, y, z):
    return 1.0 + 100.0 * np.exp(-((x - 0.5) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2) / 0.01)


def write(folder, name="DD0003"):
    """Writes the output into `folder`; returns the parameter file's path."""
    import h5py

    os.makedirs(folder, exist_ok=True)
    base = os.path.join(str(folder), name)
    with open(base, "w") as f:
        f.write(_PARAMETERS.format(density_units=DENSITY_UNITS))
    hierarchy = []
    with h5py.File(base + ".cpu0000", "w") as h5:
        for gid, level, left, right in _GRIDS:
            n = int(round((right - left) * 8 * 2 ** level))
            hierarchy.append(
                "\nGrid = {gid}\nTask = 0\nGridRank = 3\nGridDimension = {g} {g} {g}\nGridStartIndex = 3 3 3\n"
                "GridEndIndex = {e} {e} {e}\nGridLeftEdge = {l} {l} {l}\nGridRightEdge = {r} {r} {r}\nTime = 0.5\n"
                "NumberOfBaryonFields = 2\nFieldType = 0 4\nBaryonFileName = ./{name}.cpu0000\n"
                "CourantSafetyNumber = 0.3\nNumberOfParticles = 0\nGravityBoundaryType = 0\n"
                "Pointer: Grid[{gid}]->NextGridThisLevel = 0\n".format(gid=gid, g=n + 6, e=n + 2, l=left, r=right,
                                                                       name=name))
            centres = left + (np.arange(n) + 0.5) * (right - left) / n
            z, y, x = np.meshgrid(centres, centres, centres, indexing="ij")
            grid = h5.create_group("Grid%08d" % gid)
            grid["Density"] = density(x, y, z)
            grid["Temperature"] = 1e4 * density(x, y, z)
    hierarchy.append("Pointer: Grid[1]->NextGridNextLevel = 2\nPointer: Grid[2]->NextGridNextLevel = 0\n")
    with open(base + ".hierarchy", "w") as f:
        f.write("".join(hierarchy))
    with open(base + ".boundary", "w") as f:
        f.write("")
    return base
