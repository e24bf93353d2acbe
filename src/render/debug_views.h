// Debug views of the method's structure: the first visible region along a ray coloured by its
// level, brick or id (the steps view is the frame buffer's heat map of samples per ray).
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/render/frame_buffer.h"
#include "exabricks/render/scene.h"

namespace exa {

/// Colour of the level, brick or region view for one lattice ray: the first visible region's
/// (opaque), transparent where it meets none.
vec4f debugColor(const Model& model, const RegionTraversal& traversal, DebugView view, const Ray& ray,
                 FrameBuffer::TileCounters& c);

} // namespace exa
