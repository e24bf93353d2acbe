#include "exabricks/render/defaults.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/partition.h"
#include "exabricks/core/error.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace exa {

namespace {

constexpr int kBins = 256;

/// Runs `count(model, owned)` over the data: over the model (owned: null, every cell counts), or
/// over each part of a dataset held in parts (only the cells each part owns count; parts read one
/// at a time, or one per process), and then sums `sums` over the processes.
template <typename Count>
void countOverParts(const Model& model, const PartialData* part, std::vector<double>& sums, Count&& count) {
  if (part && part->eachPart)
    part->eachPart([&](const Model& m, const box3l& owned) { count(m, &owned); });
  else
    count(model, part ? &part->owned : nullptr);
  if (part && part->sumOverParts) part->sumOverParts(sums);
}

/// Volume-weighted histogram of the normalised value; returns the total volume. For a model
/// that holds part of the data, only the cells the part owns count, and the parts' histograms
/// are summed.
double histogram(const Model& model, int field, const TransferFunction& tf, std::vector<double>& hist,
                 const PartialData* part) {
  hist.assign(kBins + 1, 0.0); // the total volume last
  countOverParts(model, part, hist, [&](const Model& m, const box3l* owned) {
    const ValueArray& values = m.fieldValues.at(size_t(field));
    for (const Brick& b : m.bricks) {
      const double volume = std::ldexp(1.0, 3 * b.level);
      auto add = [&](uint32_t slot) { // one cell, weighted by its volume
        const float t = tf.normalize(values[b.valueOffset + slot]);
        hist[size_t(std::clamp(int(t * kBins), 0, kBins - 1))] += volume;
        hist[kBins] += volume;
      };
      if (owned)
        forCellsCentredIn(b, *owned, add); // a part counts only the cells it owns
      else
        for (uint32_t slot = 0; slot < b.cellCount(); ++slot)
          add(slot);
    }
  });
  const double total = hist.back();
  hist.pop_back();
  return total;
}

/// The bin holding the volume-weighted median, counted from the low or the high end.
int medianBin(const std::vector<double>& hist, double total, bool fromHigh) {
  double cumulative = 0.0;
  for (int k = 0; k < kBins; ++k) {
    const int bin = fromHigh ? kBins - 1 - k : k;
    cumulative += hist[size_t(bin)];
    if (cumulative >= 0.5 * total) return bin;
  }
  return fromHigh ? 0 : kBins - 1;
}

/// Rays cast through the data's lattice box along each axis, kRays x kRays per axis at the centres
/// of a grid over the other two axes: a small picture of what every view of the data sees.
constexpr int kRays = 128;
constexpr size_t kRayCount = size_t(3) * kRays * kRays;

/// Calls visit(ray, value index, cell width) for every cell and every ray that crosses it (along
/// its whole width); with `owned`, only the cells whose centres lie in it.
template <typename Visit>
void castAxisRays(const Model& model, const box3i& bounds, const box3l* owned, Visit&& visit) {
  double pitch[3];
  for (int a = 0; a < 3; ++a)
    pitch[a] = double(std::max(bounds.upper[a] - bounds.lower[a], 1)) / kRays;
  // The rays whose centres fall into [lo, lo + w) along axis a.
  auto span = [&](int a, int lo, int w, int& first, int& end) {
    first = std::max(0, int(std::ceil(double(lo - bounds.lower[a]) / pitch[a] - 0.5)));
    end = std::min(kRays, int(std::ceil(double(lo + w - bounds.lower[a]) / pitch[a] - 0.5)));
  };
  for (const Brick& b : model.bricks) {
    const int w = b.cellWidth();
    uint32_t slot = b.valueOffset;
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x, ++slot) {
          const vec3i lo = b.lower + vec3i(x, y, z) * w;
          if (owned && !centreInside(lo, b.level, *owned)) continue;
          for (int a = 0; a < 3; ++a) {
            const int i = (a + 1) % 3, j = (a + 2) % 3;
            int i0, i1, j0, j1;
            span(i, lo[i], w, i0, i1);
            span(j, lo[j], w, j0, j1);
            for (int rj = j0; rj < j1; ++rj)
              for (int ri = i0; ri < i1; ++ri)
                visit((size_t(a) * kRays + size_t(rj)) * kRays + size_t(ri), slot, w);
          }
        }
  }
}

box3i wholeBounds(const Model& model, const PartialData* part) {
  return part && !part->bounds.empty() ? part->bounds : model.cellBounds();
}

/// The normalised values the axis rays meet: per ray, in which of kTopBins bins of [0, 1] it met
/// cells (counts, summed over the parts).
constexpr int kTopBins = 32;
std::vector<double> valuesMet(const Model& model, int field, const TransferFunction& norm, const PartialData* part) {
  std::vector<double> counts(kRayCount * kTopBins, 0.0);
  const box3i bounds = wholeBounds(model, part);
  countOverParts(model, part, counts, [&](const Model& m, const box3l* owned) {
    const ValueArray& values = m.fieldValues.at(size_t(field));
    castAxisRays(m, bounds, owned, [&](size_t ray, uint32_t slot, int) {
      const float t = norm.normalize(values[slot]);
      if (t == t) counts[ray * kTopBins + size_t(std::clamp(int(t * kTopBins), 0, kTopBins - 1))] += 1.0;
    });
  });
  return counts;
}

/// The value (normalised) that the highest (or, with fromLow, the lowest) value met along a
/// ray reaches on the given share of the rays that meet data.
float extremeMetOnShare(const std::vector<double>& counts, bool fromLow, double share) {
  std::vector<int> extremes;
  for (size_t ray = 0; ray < kRayCount; ++ray) {
    const double* c = &counts[ray * kTopBins];
    int bin = -1;
    for (int k = 0; k < kTopBins; ++k)
      if (c[fromLow ? k : kTopBins - 1 - k] > 0.0) {
        bin = fromLow ? k : kTopBins - 1 - k;
        break;
      }
    if (bin >= 0) extremes.push_back(bin);
  }
  if (extremes.empty()) return fromLow ? 0.f : 1.f;
  const size_t n = size_t(double(extremes.size()) * share);
  const size_t k = fromLow ? std::min(n, extremes.size() - 1) : extremes.size() - 1 - std::min(n, extremes.size() - 1);
  std::nth_element(extremes.begin(), extremes.begin() + std::ptrdiff_t(k), extremes.end());
  return float(extremes[k] + (fromLow ? 0 : 1)) / kTopBins;
}

/// The share of the rays that should show the end of the colour map and gather the optical
/// depth kExposureDepth (the exposure).
constexpr double kTopShare = 0.01;
constexpr double kExposureDepth = 2.0;

/// The optical depth at opacity scale 1 into the highest values of a compact structure: each
/// value's cells taken as one blob (the cells at t or above span (volume at t or above)^(1/3)
/// finest cells).
double depthIntoStructure(const Model& model, int field, const TransferFunction& ramp, const DatasetInfo& dataset,
                          const PartialData* part) {
  std::vector<double> hist;
  const double volume = histogram(model, field, ramp, hist, part);
  if (!(volume > 0.0)) return 0.0;
  // Finest cells per lattice unit cubed: the histogram counts lattice volume.
  const double cellVolume = std::pow(double(dataset.referenceWidth), 3.0);
  double depth = 0.0, above = 0.0, outer = 0.0;
  for (int k = kBins - 1; k >= 0; --k) {
    above += hist[size_t(k)];
    const double span = std::cbrt(above / cellVolume);
    depth += double(ramp.atNormalized((float(k) + 0.5f) / kBins).w) * (span - outer);
    outer = span;
  }
  return depth;
}

/// The optical depth at opacity scale 1 that the kTopShare of the axis rays which see anything
/// (gather some depth) and gather the most reach (each cell crossed along its width; summed in
/// fixed point, so that the sum over parts equals the whole data's).
double depthOfDensestSightLines(const Model& model, int field, const TransferFunction& ramp, const DatasetInfo& dataset,
                                const PartialData* part) {
  constexpr double kFixed = 1 << 20;
  std::vector<double> depth(kRayCount, 0.0); // in kFixed units
  const box3i bounds = wholeBounds(model, part);
  countOverParts(model, part, depth, [&](const Model& m, const box3l* owned) {
    const ValueArray& values = m.fieldValues.at(size_t(field));
    castAxisRays(m, bounds, owned, [&](size_t ray, uint32_t slot, int width) {
      const double alpha = std::round(double(ramp.lookup(values[slot]).w) * kFixed);
      depth[ray] += alpha * std::ldexp(1.0, int(std::lround(std::log2(double(width) / dataset.referenceWidth))));
    });
  });
  std::vector<double> seeing;
  for (double d : depth)
    if (d > 0.0) seeing.push_back(d / kFixed);
  if (seeing.empty()) return 0.0;
  const size_t k = seeing.size() - 1 - std::min(seeing.size() - 1, size_t(double(seeing.size()) * kTopShare));
  std::nth_element(seeing.begin(), seeing.begin() + std::ptrdiff_t(k), seeing.end());
  return seeing[k];
}

/// The opacity scale of the first picture's exposure: both the densest lines of sight and the
/// path into a compact structure's highest values gather at least kExposureDepth (the first
/// keeps a web of thin structures from staying faint, the second a solid body from turning
/// translucent).
float exposureScale(const Model& model, int field, const TransferFunction& tf, const DatasetInfo& dataset,
                    const PartialData* part) {
  TransferFunction ramp = tf;
  ramp.opacityScale = 1.f;
  const double depth = std::min(depthOfDensestSightLines(model, field, ramp, dataset, part),
                                depthIntoStructure(model, field, ramp, dataset, part));
  if (!(depth > 0.0)) return dataset.defaultOpacityScale;
  return float(std::clamp(kExposureDepth / depth, 1e-6, 1.0));
}

/// What adaptTransferFunction works on: the field, the value range it maps and the histogram of
/// the field's volume over it.
struct Adapting {
  const Model& model;
  const DatasetInfo& dataset;
  int field;
  const PartialData* part;
  const TransferFunction& tfIn;
  DefaultChoices& out;
  const std::string& name;
  range1f range;
  TransferFunction norm;
  std::vector<double> hist;
  double total = 0.0;
};

/// A constant field (to a few float steps): nothing invented to draw, and said so. True when it
/// is one.
bool drawConstant(Adapting& a) {
  const range1f& range = a.range;
  const float scale = std::max(std::abs(range.lower), std::abs(range.upper));
  if (range.upper - range.lower > 4.f * std::numeric_limits<float>::epsilon() * scale) return false;
  a.out.tf.opacity = {{0.f, 0.f}, {1.f, 0.f}};
  a.out.note(strCat("'", a.name, "' is constant (", range.lower, "): nothing to draw"),
             "--range and --opacity draw it all the same");
  return true;
}

/// Signed values (velocities, fluctuations): a diverging colour map centred on zero, opaque
/// towards both ends, both signs shown. True when the field takes both signs so.
bool drawSigned(Adapting& a) {
  TransferFunction& tf = a.out.tf;
  const float negative = -a.range.lower, positive = a.range.upper;
  if (tf.logScale || !(negative > 0.f && positive > 0.f) ||
      std::min(negative, positive) < 0.1f * std::max(negative, positive))
    return false;
  const float m = std::max(negative, positive);
  tf.colorMap = builtinColorMap("cool-to-warm");
  tf.valueRange = range1f{-m, m};
  tf.opacity = {{0.f, 1.f}, {0.25f, 0.25f}, {0.5f, 0.f}, {0.75f, 0.25f}, {1.f, 1.f}};
  if (a.tfIn.opacityScale == 0.f) tf.opacityScale = exposureScale(a.model, a.field, tf, a.dataset, a.part);
  a.out.note(
      strCat("'", a.name, "' takes both signs: a diverging colour map over [", -m, ", ", m, "], transparent at zero"),
      "--colormap, --range, --opacity to choose");
  return true;
}

/// The histogram over the range, and logarithmic mapping where a linear one would crowd most of
/// the volume into the lowest percent of the colour map: positive values over more than three
/// decades, half the volume below 1 % of the range. Exact zeros beside positive values over
/// decades (a density with empty cells): the positive values decide, and zeros sit below the
/// range. False when the field has no volume to histogram.
bool chooseMapping(Adapting& a, bool autoLog) {
  TransferFunction& tf = a.out.tf;
  range1f& range = a.range;
  const float lowest = a.dataset.valueRanges.at(size_t(a.field)).lower;
  if (autoLog && !tf.logScale && range.lower == 0.f && range.upper > 0.f && !a.model.fieldValues.empty()) {
    float smallest = std::numeric_limits<float>::infinity();
    auto scan = [&](const Model& m) {
      for (float v : m.fieldValues.at(size_t(a.field)))
        if (v > 0.f) smallest = std::min(smallest, v);
    };
    if (a.part && a.part->eachPart)
      a.part->eachPart([&](const Model& m, const box3l&) { scan(m); });
    else
      scan(a.model);
    if (smallest < range.upper * 1e-3f) range.lower = smallest;
  }
  a.norm = tf;
  a.norm.valueRange = range;
  a.total = histogram(a.model, a.field, a.norm, a.hist, a.part);
  if (!(a.total > 0.0)) return false;
  if (autoLog && !tf.logScale && range.lower > 0.f && range.upper > 1e3f * range.lower &&
      medianBin(a.hist, a.total, false) < kBins / 100) {
    tf.logScale = a.norm.logScale = true;
    a.total = histogram(a.model, a.field, a.norm, a.hist, a.part);
    const bool zeros = lowest == 0.f;
    a.out.note(
        strCat("'", a.name, "' is positive", zeros ? " (besides exact zeros, drawn as the lowest)" : "", ", spans ",
               std::lround(std::log10(double(range.upper) / double(range.lower))),
               " decades and half its volume lies in the lowest percent of the range: ", "logarithmic colour mapping"),
        "--linear to refuse");
    if (zeros && a.tfIn.valueRange.empty()) tf.valueRange = range;
  } else if (range.lower != lowest && a.tfIn.valueRange.empty()) {
    range.lower = lowest; // zeros, but no log: the whole range
    a.norm.valueRange = range;
    a.total = histogram(a.model, a.field, a.norm, a.hist, a.part);
  }
  return true;
}

/// Where the background lies in the histogram: the value filling the most volume, with its
/// neighbours while they hold a tenth of its volume or more, when it fills a fifth of the
/// volume or more; and at least the half of the volume on its side (the volume-weighted median).
struct Background {
  double share = 0.0;
  bool dominant = false, high = false;
  float tLo = 0.f, tHi = 1.f; ///< normalised values it spans
};

Background backgroundOf(const std::vector<double>& hist, double total) {
  Background b;
  const int mode = int(std::max_element(hist.begin(), hist.end()) - hist.begin());
  b.share = hist[size_t(mode)] / total;
  b.dominant = b.share >= 0.2;
  int lo = mode, hi = mode;
  while (lo > 0 && hist[size_t(lo - 1)] >= 0.1 * hist[size_t(mode)])
    --lo;
  while (hi < kBins - 1 && hist[size_t(hi + 1)] >= 0.1 * hist[size_t(mode)])
    ++hi;
  b.high = b.dominant && (float(mode) + 0.5f) / kBins > 2.f / 3.f;
  const int median = medianBin(hist, total, b.high);
  b.tLo = float(b.dominant ? std::min(lo, median) : median) / kBins;
  b.tHi = float((b.dominant ? std::max(hi, median) : median) + 1) / kBins;
  return b;
}

/// The colour map and the opacity ramp span what lies beyond the background: the value range
/// starts (or ends) where the background ends. The far end of the colour map: the value that the
/// most extreme structures reach along kTopShare of the axis rays that meet data, where that
/// lies a tenth of the range or more inside it (a few small dense haloes do not stretch the
/// colour map so far that the picture never shows its end); values beyond it show the end
/// colour. False where the background leaves nothing beyond it.
bool spanBeyondBackground(Adapting& a, const Background& b) {
  TransferFunction& tf = a.out.tf;
  auto valueAt = [&](float t) {
    double l = a.range.lower, h = a.range.upper;
    if (!tf.logScale) return float(l + (h - l) * double(t));
    if (!(l > 0.0)) l = h * 1e-6;
    return float(std::pow(10.0, std::log10(l) + (std::log10(h) - std::log10(l)) * double(t)));
  };
  const float tFar = extremeMetOnShare(valuesMet(a.model, a.field, a.norm, a.part), b.high, kTopShare);
  std::string farNote;
  if (b.high && b.tLo > 0.f) {
    const float tEnd = tFar > 0.1f && tFar < 0.75f * b.tLo ? tFar : 0.f;
    tf.valueRange = range1f{valueAt(tEnd), valueAt(b.tLo)};
    tf.opacity = {{0.f, 1.f}, {0.25f, 0.5625f}, {0.5f, 0.25f}, {0.75f, 0.0625f}, {1.f, 0.f}};
    if (tEnd > 0.f) farNote = "the lowest";
  } else if (!b.high && b.tHi < 1.f) {
    const float tEnd = tFar < 0.9f && tFar > b.tHi + 0.25f * (1.f - b.tHi) ? tFar : 1.f;
    tf.valueRange = range1f{valueAt(b.tHi), valueAt(tEnd)};
    tf.opacity = {{0.f, 0.f}, {0.25f, 0.0625f}, {0.5f, 0.25f}, {0.75f, 0.5625f}, {1.f, 1.f}};
    if (tEnd < 1.f) farNote = "the highest";
  } else {
    return false;
  }
  if (!farNote.empty())
    a.out.note(strCat("the colour map ends at ", b.high ? tf.valueRange.lower : tf.valueRange.upper, ", which ",
                      farNote, " values reach along ", 100.0 * kTopShare,
                      " % of the lines of sight (beyond it: the end colour)"),
               "--range to choose");
  return true;
}

/// Exposure (the lines of sight that gather the most reach optical depth kExposureDepth) and
/// what the choice of the range says.
void exposeAndSay(Adapting& a, const Background& b) {
  TransferFunction& tf = a.out.tf;
  if (a.tfIn.opacityScale == 0.f) {
    tf.opacityScale = exposureScale(a.model, a.field, tf, a.dataset, a.part);
    a.out.note(strCat("exposure: opacity scale ", tf.opacityScale, " (optical depth ", kExposureDepth,
                      " along the densest ", 100.0 * kTopShare,
                      " % of the lines of sight and into the highest values)"),
               "--opacity-scale to choose");
  }
  if (b.dominant)
    a.out.note(strCat(std::lround(100.0 * b.share), " % of the volume holds '", a.name,
                      "' near one value (the background): transparent there; colours and opacity span [",
                      tf.valueRange.lower, ", ", tf.valueRange.upper, "]"),
               "--range, --opacity to choose");
  else
    a.out.note(strCat("transparent over the ", b.high ? "upper" : "lower", " half of the volume of '", a.name,
                      "'; colours and opacity span [", tf.valueRange.lower, ", ", tf.valueRange.upper, "]"),
               "--range, --opacity to choose");
}

} // namespace

DefaultChoices adaptTransferFunction(const Model& model, const DatasetInfo& dataset, int field,
                                     const TransferFunction& tfIn, bool autoLog, bool autoOpacity,
                                     const PartialData* part, bool autoColorMap) {
  DefaultChoices out;
  out.tf = tfIn;
  const range1f range = tfIn.valueRange.empty() ? dataset.valueRanges.at(size_t(field)) : tfIn.valueRange;
  if (range.empty()) return out;
  Adapting a{model, dataset, field, part, tfIn, out, model.fieldNames.at(size_t(field)), range, {}, {}, 0.0};
  const bool chooseRange = autoOpacity && tfIn.valueRange.empty();
  if (chooseRange && drawConstant(a)) return out;
  if (chooseRange && autoColorMap && drawSigned(a)) return out;
  if (!chooseMapping(a, autoLog)) return out;
  if (!autoOpacity || !tfIn.valueRange.empty()) return out; // a range given is kept
  const Background b = backgroundOf(a.hist, a.total);
  if (!spanBeyondBackground(a, b)) return out;
  if (!(out.tf.valueRange.upper > out.tf.valueRange.lower)) {
    out.tf.valueRange = tfIn.valueRange;
    out.tf.opacity = tfIn.opacity;
    return out;
  }
  exposeAndSay(a, b);
  return out;
}

TransferFunction widenedForSeries(const TransferFunction& adapted, const range1f& step, const range1f& series) {
  TransferFunction tf = adapted;
  range1f& r = tf.valueRange;
  if (r.empty() || step.empty() || series.empty()) {
    r = series;
    return tf;
  }
  if (r.lower < 0.f && r.lower == -r.upper) { // centred on zero
    const float m = std::max({r.upper, -series.lower, series.upper});
    r = range1f{-m, m};
    return tf;
  }
  TransferFunction unit = adapted;
  unit.opacityScale = 1.f;
  const float opacityLow = unit.atNormalized(0.f).w, opacityHigh = unit.atNormalized(1.f).w;
  const bool ratios = tf.logScale && step.lower > 0.f && series.lower > 0.f;
  if (r.lower <= step.lower)
    r.lower = std::min(r.lower, series.lower);
  else if (opacityLow > opacityHigh && series.lower < step.lower)
    r.lower = ratios ? r.lower * (series.lower / step.lower) : r.lower - (step.lower - series.lower);
  if (r.upper >= step.upper)
    r.upper = std::max(r.upper, series.upper);
  else if (opacityHigh > opacityLow && series.upper > step.upper)
    r.upper = ratios ? r.upper * (series.upper / step.upper) : r.upper + (series.upper - step.upper);
  return tf;
}

void DefaultChoices::note(std::string text, std::string hint) {
  notes.push_back(std::move(text));
  hints.push_back(std::move(hint));
}

std::vector<std::string> DefaultChoices::commandLineNotes() const {
  std::vector<std::string> out;
  for (size_t i = 0; i < notes.size(); ++i)
    out.push_back(i < hints.size() && !hints[i].empty() ? strCat(notes[i], " (", hints[i], ")") : notes[i]);
  return out;
}

std::vector<std::string> sceneWarnings(const Scene& scene, const Model& model, const DatasetInfo& dataset) {
  std::vector<std::string> out;
  if (!scene.volume && scene.iso.values.empty() && scene.meshes.empty())
    out.push_back("nothing to draw: the volume is off and there are no iso-surfaces or meshes");
  auto fieldOf = [&](const std::string& name) { return model.requireField(name); };
  auto describe = [](const range1f& r) { return strCat("[", r.lower, ", ", r.upper, "]"); };
  if (scene.volume)
    for (const VolumeLayer& layer : scene.layers) {
      const int f = fieldOf(layer.field);
      const std::string& name = model.fieldNames[size_t(f)];
      const range1f data = dataset.valueRanges.at(size_t(f));
      const range1f& r = layer.tf.valueRange;
      if (!r.empty() && !data.empty() && (r.upper < data.lower || r.lower > data.upper))
        out.push_back(strCat("the value range ", describe(r), " excludes all of '", name, "' (its values lie in ",
                             describe(data), "): every sample maps to one end of the colour map"));
      if (layer.tf.logScale && !data.empty() && !(data.upper > 0.f))
        out.push_back(strCat("'", name, "' has no positive values (", describe(data),
                             "): with logarithmic mapping every sample maps to the low end"));
    }
  // Settings that do nothing with the integrator chosen.
  const bool albedoPoints =
      std::any_of(scene.layers.begin(), scene.layers.end(), [](const VolumeLayer& l) { return !l.tf.albedo.empty(); });
  if (scene.integration.integrator == Integrator::March && (scene.pathTracing != PathTracing{} || albedoPoints))
    out.push_back("the path-tracing settings (pathtrace.*, albedo points) do nothing with the ray marcher: "
                  "--integrator pathtrace (scene key integration.integrator) uses them");
  if (scene.integration.integrator == Integrator::PathTrace && scene.volume && scene.pathTracing.bounces == 0 &&
      !(scene.pathTracing.emission > 0.f))
    out.push_back("zero bounces without emission: no light leaves the volume toward the camera, so it is drawn "
                  "black; raise --bounces or give the volume --emission");
  if (!scene.iso.values.empty()) {
    const std::string& isoName = !scene.iso.field.empty() ? scene.iso.field
                                 : !scene.layers.empty()  ? scene.layers[0].field
                                                          : std::string();
    const int f = fieldOf(isoName);
    const range1f data = dataset.valueRanges.at(size_t(f));
    for (float v : scene.iso.values)
      if (data.empty() || v < data.lower || v > data.upper)
        out.push_back(strCat("iso-value ", v, " lies outside the range of '", model.fieldNames[size_t(f)], "' ",
                             describe(data), ": that surface does not exist"));
  }
  return out;
}

bool imageIsEmpty(const Image& image) {
  for (const vec4f& p : image.pixels)
    if (p.w > 0.f) return false;
  return true;
}

Scene framingScene(Scene scene) {
  scene.shading = Shading::None;
  return scene;
}

box3d visibleBoundsOf(const Model& model, const DatasetInfo& dataset, const Scene& scene) {
  Renderer framing(model, dataset);
  framing.setScene(framingScene(scene));
  return framing.visibleBounds();
}

} // namespace exa
