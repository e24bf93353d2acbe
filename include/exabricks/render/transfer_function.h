// Transfer functions: a colour map and a piecewise-linear opacity over a value range (linear or
// logarithmic). Opacity is per finest cell width: the ray marcher corrects it for its step.
#pragma once

#include "exabricks/core/color.h"

#include <string>
#include <vector>

namespace exa {

/// A colour map: control points at increasing positions in [0, 1] with linear-RGB colours,
/// interpolated linearly between them.
struct ColorMap {
  std::string name;
  std::vector<float> positions; ///< increasing, first 0, last 1
  std::vector<vec3f> colors;    ///< linear RGB in [0, 1], one per position
  vec3f at(float t) const;      ///< t is clamped to [0, 1]
  friend bool operator==(const ColorMap&, const ColorMap&) = default;
};

/// Names of the built-in colour maps: viridis, plasma, inferno, magma, cool-to-warm, grayscale.
const std::vector<std::string>& builtinColorMapNames();
/// A built-in colour map by name; throws exa::Error listing the names when unknown.
ColorMap builtinColorMap(const std::string& name);

/// One opacity control point; x is the normalised value in [0, 1].
struct OpacityPoint {
  float x = 0;
  float alpha = 0;
  friend bool operator==(const OpacityPoint&, const OpacityPoint&) = default;
};

class TransferFunction {
public:
  ColorMap colorMap;
  std::vector<OpacityPoint> opacity; ///< increasing x; empty means a linear ramp 0 -> 1
  /// The path tracer's single-scattering albedo over the normalised value (x, albedo in [0, 1]),
  /// piecewise linear as the opacity; empty: the scene's albedo.
  std::vector<OpacityPoint> albedo;
  range1f valueRange;       ///< values mapped to [0, 1]; empty: not set yet
  bool logScale = false;    ///< map log10(value) (values <= 0 map to 0)
  float opacityScale = 1.f; ///< multiplies every opacity (0 in a Scene: the dataset default)

  /// Value -> [0, 1] (clamped), linear or logarithmic over valueRange.
  float normalize(float value) const;
  /// Linear-RGB colour and opacity (per finest cell width) of a value.
  vec4f lookup(float value) const;
  /// The same for a normalised value t in [0, 1]: lookup(v) == atNormalized(normalize(v)).
  vec4f atNormalized(float t) const;
  /// Exact maximum opacity over all values in [r.lower, r.upper] (used for space skipping).
  float maxOpacity(const range1f& r) const;

  friend bool operator==(const TransferFunction&, const TransferFunction&) = default;
};

/// The table the ray marcher looks opacity and colour up in (render/sample_math.h): kTfTableSize
/// entries over the normalised value, colour in xyz and log2(1 - alpha) in w (so that opacity
/// correction is one exp2), alpha capped just below one.
std::vector<vec4f> tabulateTransferFunction(const TransferFunction& tf);

/// The albedo table of a transfer function with its own albedo: kTfTableSize entries over the
/// normalised value, as tabulateTransferFunction's; empty without one.
std::vector<float> tabulateAlbedo(const TransferFunction& tf);

/// The default of a scene: the named built-in colour map, a linear opacity ramp, the field's
/// range and the dataset's default opacity scale (opacityScale 0).
TransferFunction defaultTransferFunction(const std::string& colorMap = "viridis");

/// A transfer function from JSON text: a ParaView colour-map preset (a JSON array or object with
/// "RGBPoints" and optional "Points" for opacity, "ColorSpace", "Name") or an exabricks JSON
/// object (see docs/transfer-functions.md). The value range in the text, if any, is kept in
/// valueRange (a preset's is the span of its points; `isPreset` says which form it had, for
/// callers that rescale presets to the data as ParaView does); errors name `source` and the
/// problem. documents/transfer_function_file.h reads files.
TransferFunction parseTransferFunction(const std::string& jsonText, const std::string& source,
                                       bool* isPreset = nullptr);
/// The exabricks JSON form of a transfer function (built-in colour maps by name, others as
/// points; an opacity scale of 0 as "auto").
std::string transferFunctionJson(const TransferFunction& tf);

} // namespace exa
