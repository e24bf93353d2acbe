"""Datasets: exabricks.Dataset, and the ways to make one (load, from_cells, from_grids)."""

import json

import numpy as np

from . import _core


class Dataset:
    """A built AMR dataset (bricks and active brick regions over leaf cells)."""

    def __init__(self, core, path=None):
        self._core = core
        self._path = path
        # Where particles come from other than the input's files (from_yt: yt), given a species
        # name ("" every species, None their list).
        self._particle_source = None

    @property
    def name(self):
        return self._core.name

    @property
    def fields(self):
        """Field names, in file order."""
        return list(self._core.fields)

    @property
    def units(self):
        """Units per field name, as the input states them ("" where unknown): read by the file's
        reader, given to from_cells / from_grids, or taken from yt by from_yt."""
        return dict(zip(self._core.fields, self._core.units))

    def field_units(self, name=None):
        """The units of a field (the default field when None); "" where unknown."""
        fields = list(self._core.fields)
        name = name or self.default_field
        if name not in fields:
            raise ValueError("unknown field '%s' (the dataset has %s)" % (name, ", ".join(fields)))
        return self._core.units[fields.index(name)]

    def field_label(self, name=None):
        """The title the command line's colour bar gives a field: "name [units]", or the name
        alone where its units are unknown."""
        name = name or self.default_field
        units = self.field_units(name)
        return "%s [%s]" % (name, units) if units else name

    @property
    def cells(self):
        return self._core.cells

    @property
    def memory(self):
        """For a step held in parts (load's memory_budget): its budget, parts, the parts resident
        and read so far, the largest part's estimated bytes and the process's peak resident
        memory; None for a dataset held whole."""
        return self._core.memory

    @property
    def bounds(self):
        """World box ((x0, y0, z0), (x1, y1, z1)) of the cells."""
        return self._core.bounds

    @property
    def default_field(self):
        return self._core.default_field()

    @property
    def opacity_reference_width(self):
        """The world length opacity is given per: the finest cell's width (averaged over the
        axes where the spacing differs)."""
        return self._core.opacity_reference_width

    @property
    def default_opacity_scale(self):
        """The opacity scale "auto" stands for: a ray through the whole data gathers an optical
        depth of about eight."""
        return self._core.default_opacity_scale

    def info(self):
        """The dictionary `exabricks info --json` prints."""
        return json.loads(self._core.info_json())

    @property
    def particle_species(self):
        """The particle species beside the cells, from the input's headers: a list of dicts
        (name, count, attributes, precision); empty for inputs without particles (the embedded
        dataset, model files, from_cells and from_grids datasets)."""
        if self._particle_source is not None:
            return list(self._particle_source(None).values())
        return _core.list_particles(self._path) if self._path else []

    def particles(self, species=None):
        """The particles of one species as a dict of numpy arrays: "position" (N, 3) in world
        coordinates, as the cells, and each attribute by name (N,) (float64; integer attributes
        such as ids and types int64). With no species, a dict of every species' dict by name.
        Particles with a NaN coordinate are skipped (said on stderr)."""
        if self._particle_source is not None:
            read = self._particle_source(species or "")
            return read[species] if species is not None else read
        if not self._path:
            if species is not None:
                raise ValueError("no particle species '%s' (this dataset holds no particles)" % species)
            return {}
        read = _core.read_particles(self._path, species or "")
        return read[species] if species is not None else read

    def add_particles(self, species, position, **attributes):
        """Particles from arrays, drawn by the scenes made after this: `position` (N, 3) in world
        coordinates and each attribute an (N,) array by name (integer arrays stay integers).
        Species added so replace the input's own particles."""
        position = np.ascontiguousarray(position, dtype=np.float64)
        if position.ndim != 2 or position.shape[1] != 3:
            raise ValueError("position must be an (N, 3) array")
        given = {"position": position}
        for name, values in attributes.items():
            values = np.asarray(values)
            if values.shape != (position.shape[0],):
                raise ValueError("attribute '%s' must be an (N,) array of %d values" % (name, position.shape[0]))
            given[name] = values
        arrays = getattr(self, "_arrays", {})
        arrays[str(species)] = given
        self._arrays = arrays

        def source(wanted):
            if wanted is None:
                return {n: {"name": n, "count": int(d["position"].shape[0]),
                            "attributes": [k for k in d if k != "position"], "precision": "double"}
                        for n, d in arrays.items()}
            if wanted and wanted not in arrays:
                raise ValueError("no particle species '%s' (given: %s)" % (wanted, ", ".join(arrays)))
            return {n: d for n, d in arrays.items() if not wanted or n == wanted}
        self._particle_source = source
        self._core.set_particles([(n, d["position"], {k: v for k, v in d.items() if k != "position"})
                                  for n, d in arrays.items()])
        self._particles_given = True

    def sample(self, points, field=None):
        """Values (N,) and gradients per world unit (N, 3) at world positions (N, 3); NaN where
        no cell has weight."""
        points = np.asarray(points, dtype=np.float64)
        if points.ndim == 1 and points.shape[0] == 3:
            points = points.reshape(1, 3)
        return self._core.sample(points, field or "")

    def __repr__(self):
        return "<exabricks.Dataset %s: %d cells, fields %s>" % (self.name, self.cells, ", ".join(self.fields))


def load(path=None, fields=None, max_brick_width=32, box=None, nan_as_holes=False, memory_budget=None):
    """Reads any input the command line reads (model file, NAME.cells, AMReX, Chombo, FLASH, Enzo,
    VTK AMR, raw volume; the embedded default dataset when path is None) and builds it.
    `box` (x0, y0, z0, x1, y1, z1, finest lattice units) keeps only the cells that overlap it.
    `nan_as_holes`: cells with a NaN or infinite value in any loaded field become holes (dropped
    from every field, counted on stderr) instead of an error (as `--nan-as-holes`).
    `memory_budget` ("512M", "2G", or bytes): the most resident memory for the whole process, as
    the command line's `--memory-budget`; a step that does not fit is held in parts, read as
    renders and samples need them, and drawn part by part (equal to the whole step's picture);
    `Dataset.memory` then describes the parts. A budget too small raises an error naming the
    smallest that works."""
    budget = "" if memory_budget is None else str(int(memory_budget)) if isinstance(memory_budget, int) \
        else str(memory_budget)
    return Dataset(_core.load("" if path is None else str(path), list(fields or []), max_brick_width,
                              list(box) if box is not None else [], bool(nan_as_holes), budget),
                   None if path is None else str(path))


def _units_list(units, names):
    """Units per name from a dict (missing names have none) or a list in the names' order."""
    if units is None:
        return []
    if isinstance(units, dict):
        unknown = [k for k in units if k not in names]
        if unknown:
            raise ValueError("units given for %s, which are not among the fields %s" % (unknown, list(names)))
        return [str(units.get(n) or "") for n in names]
    units = [str(u or "") for u in units]
    if len(units) != len(names):
        raise ValueError("%d units given for %d fields" % (len(units), len(names)))
    return units


def from_cells(corners, levels, fields, origin=(0.0, 0.0, 0.0), spacing=(1.0, 1.0, 1.0), max_brick_width=32,
               units=None):
    """A dataset from leaf cells: integer lower corners (N, 3) in finest-lattice units, levels (N,)
    (a cell is 2**level finest cells wide; corners are multiples of the width), and one (N,) array
    per field in a dict. World = origin + spacing * lattice. A non-dict `fields` is the field
    "scalar". `units`: a dict of units per field name (or a list in field order)."""
    if not isinstance(fields, dict):
        fields = {"scalar": fields}
    pairs = [(str(name), np.asarray(values)) for name, values in fields.items()]
    unit_list = _units_list(units, [name for name, _ in pairs])
    for name, values in pairs:
        if values.dtype.kind not in "fiu":
            raise ValueError("field '%s' must hold numbers, not %s" % (name, values.dtype))
    corners = np.asarray(corners)
    levels = np.asarray(levels)
    if corners.dtype.kind not in "iu" or levels.dtype.kind not in "iu":
        raise ValueError("corners and levels must be integer arrays (finest-lattice units)")
    return Dataset(_core.from_cells(corners, levels, pairs, list(map(float, origin)), list(map(float, spacing)),
                                    max_brick_width, unit_list))


def from_grids(grids, fields=None, bbox=None, max_brick_width=32, units=None):
    """A dataset from overlapping grids in the layout yt's load_amr_grids takes: a list of dicts
    with "left_edge", "right_edge", "level", "dimensions" and one array per field of shape
    `dimensions` (indexed [i, j, k]). Cells covered by a finer grid are dropped. `bbox`
    ([[x0, x1], [y0, y1], [z0, z1]], optional) gives the domain, whose lower corner is the lattice
    origin. `units`: a dict of units per field name (or a list in field order)."""
    if not grids:
        raise ValueError("from_grids: no grids")
    reserved = {"left_edge", "right_edge", "level", "dimensions"}
    names = list(fields) if fields else [k for k in grids[0] if k not in reserved]
    if not names:
        raise ValueError("from_grids: the grids hold no field arrays")
    packed = []
    for g, grid in enumerate(grids):
        dims = [int(d) for d in grid["dimensions"]]
        arrays = []
        for name in names:
            if name not in grid:
                raise ValueError("from_grids: grid %d has no field '%s'" % (g, name))
            a = np.asarray(grid[name], dtype=np.float64)
            if list(a.shape) != dims:
                raise ValueError("from_grids: grid %d field '%s' has shape %s, dimensions are %s"
                                 % (g, name, tuple(a.shape), tuple(dims)))
            arrays.append(np.ascontiguousarray(a.transpose(2, 1, 0)).ravel())  # x fastest
        packed.append((list(map(float, grid["left_edge"])), list(map(float, grid["right_edge"])), dims, arrays))
    origin = [float(bbox[a][0]) for a in range(3)] if bbox is not None else []
    names = [str(n) for n in names]
    return Dataset(_core.from_grids(packed, names, origin, max_brick_width, _units_list(units, names)))
