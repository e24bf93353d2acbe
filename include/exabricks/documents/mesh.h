// Triangle meshes (surfaces to show with the volume): OBJ, PLY and the binary `.tris` format.
//
// `.tris` is little-endian and holds meshes one after another until the end of the file, each
// `int32 numVerts, float32[3] x numVerts, int32 numTris, int32[3] x numTris`, with indices into
// that mesh's own vertices. Every file is read into one mesh: the meshes of a `.tris` file and
// the groups and objects of an OBJ file are merged, polygons are fan-triangulated.
#pragma once

#include "exabricks/core/mesh.h"

#include <string>
#include <vector>

namespace exa {

/// Reads OBJ, PLY (ascii, binary_little_endian, binary_big_endian) or the binary `.tris` format.
/// PLY is known by its "ply" magic line; `.tris` and `.obj` by extension (and `.tris` also by
/// structure). Several meshes in one file are merged into one mesh. Errors (exa::Error) name
/// the file, the record (line number in text, element index and byte offset in binary data)
/// and the problem: truncated data, impossible counts, indices out of range, non-finite
/// coordinates, malformed lines, missing PLY properties, no triangles at all.
TriangleMesh readMesh(const std::string& path);

} // namespace exa
