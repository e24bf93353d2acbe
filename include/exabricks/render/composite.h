// Sort-last compositing of data-parallel rendering: the images of parts of the data that do not
// overlap along any ray (the boxes of a k-d partition) combine front to back with the "over"
// operator on premultiplied colour, one pass at a time.
#pragma once

#include "exabricks/render/frame_buffer.h"

#include <cstddef>

namespace exa {

/// Floats per pixel of a part's image as it is exchanged: premultiplied RGBA and the volume
/// samples taken (summed, for the steps view).
constexpr size_t kCompositeChannels = 5;

/// out = parts[0] over parts[1] over ... (front first), for `pixels` pixels of
/// kCompositeChannels floats each.
inline void compositeFrontToBack(const float* const* parts, size_t partCount, size_t pixels, float* out) {
  for (size_t p = 0; p < pixels; ++p) {
    float r = 0.f, g = 0.f, b = 0.f, a = 0.f, steps = 0.f;
    for (size_t k = 0; k < partCount; ++k) {
      const float* c = parts[k] + p * kCompositeChannels;
      const float t = 1.f - a;
      r += t * c[0];
      g += t * c[1];
      b += t * c[2];
      a += t * c[3];
      steps += c[4];
    }
    float* o = out + p * kCompositeChannels;
    o[0] = r, o[1] = g, o[2] = b, o[3] = a, o[4] = steps;
  }
}

/// One pass of a buffer (cleared before the pass) as kCompositeChannels floats per pixel.
inline void packForCompositing(const FrameBuffer::Sums& s, size_t pixels, float* out) {
  for (size_t p = 0; p < pixels; ++p) {
    float* o = out + p * kCompositeChannels;
    for (size_t c = 0; c < 4; ++c)
      o[c] = s.colors[4 * p + c];
    o[4] = s.steps[p];
  }
}

/// A composited pass added to the buffer as one more pass of every tile.
inline void addComposited(const float* result, size_t pixels, FrameBuffer& buffer) {
  const FrameBuffer::Sums out = buffer.sums();
  for (size_t p = 0; p < pixels; ++p) {
    const float* c = result + p * kCompositeChannels;
    for (size_t ch = 0; ch < 4; ++ch) {
      out.colors[4 * p + ch] += c[ch];
      out.squares[4 * p + ch] += c[ch] * c[ch];
    }
    out.steps[p] += c[4];
  }
  for (size_t t = 0; t < out.tiles; ++t)
    ++out.tilePasses[t];
}

} // namespace exa
