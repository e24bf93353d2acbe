#include "exabricks/io/amrex_write.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <unordered_map>

namespace exa {
namespace fs = std::filesystem;

namespace {

/// Data files are started anew past this size.
constexpr uint64_t kFileBytes = uint64_t(2) << 30;

std::string boxText(const vec3l& lo, const vec3l& hi) {
  return strCat("((", lo.x, ",", lo.y, ",", lo.z, ") (", hi.x, ",", hi.y, ",", hi.z, ") (0,0,0))");
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// One level's cells of a piece in boxes of `edge`^3 cells aligned to multiples of `edge`.
struct PieceBoxes {
  struct Box {
    vec3l origin;              ///< first cell, level index space
    std::vector<float> values; ///< edge^3 cells x fields (fields fastest)
    std::vector<uint8_t> present, children;
  };
  int64_t edge = 8;
  size_t fields = 1;
  std::unordered_map<uint64_t, size_t> index;
  std::vector<Box> boxes;

  /// The box and slot of level cell c, made when absent.
  std::pair<Box*, size_t> at(const vec3l& c) {
    const vec3l b(c.x / edge, c.y / edge, c.z / edge);
    if (b.x >= (1 << 21) || b.y >= (1 << 21) || b.z >= (1 << 21)) fail("AMReX writer: lattice too large");
    const uint64_t key = (uint64_t(b.z) << 42) | (uint64_t(b.y) << 21) | uint64_t(b.x);
    auto [it, added] = index.emplace(key, boxes.size());
    if (added) {
      Box box;
      box.origin = b * edge;
      const size_t n = size_t(edge * edge * edge);
      box.values.assign(n * fields, 0.0f);
      box.present.assign(n, 0);
      box.children.assign(n, 0);
      boxes.push_back(std::move(box));
    }
    Box& box = boxes[it->second];
    const vec3l l = c - box.origin;
    return {&box, size_t((l.z * edge + l.y) * edge + l.x)};
  }
};

} // namespace

struct AmrexPlotfileWriter::Level {
  int64_t cells = 0; ///< per axis
  int64_t edge = 8;
  std::vector<std::pair<vec3l, vec3l>> boxes; ///< inclusive corners
  std::vector<std::string> files;
  std::vector<uint64_t> offsets;
  std::vector<double> minima, maxima; ///< per box, per field
  std::ofstream data;
  std::string dataName;
  uint64_t written = 0;
  int fileCount = 0;
};

AmrexPlotfileWriter::AmrexPlotfileWriter(std::string path, std::vector<std::string> fieldNames, int levels,
                                         int64_t latticeWidth, bool float32)
    : path_(std::move(path)), names_(std::move(fieldNames)), levels_(levels), width_(latticeWidth), float32_(float32) {
  if (levels_ < 1 || levels_ > 20) fail(path_, ": cannot write ", levels_, " levels");
  if (names_.empty()) fail(path_, ": no fields to write");
  std::error_code ec;
  if (fs::exists(path_, ec)) {
    std::ifstream header(fs::path(path_) / "Header");
    std::string first;
    if (!fs::is_directory(path_, ec) || !header || !std::getline(header, first) || first.rfind("HyperCLaw", 0) != 0)
      fail(path_, ": exists and is not an AMReX plotfile; not overwritten");
  }
  partial_ = path_ + ".partial";
  fs::remove_all(partial_, ec);
  for (int l = 0; l < levels_; ++l) {
    const int exaLevel = levels_ - 1 - l;
    auto level = std::make_unique<Level>();
    level->cells = width_ >> exaLevel;
    level->edge = l == 0 ? kSlabCells : std::min<int64_t>(32, int64_t(kSlabCells) << l);
    fs::create_directories(fs::path(partial_) / ("Level_" + std::to_string(l)), ec);
    if (ec) fail(partial_, ": cannot create the plotfile's folders: ", ec.message());
    perLevel_.push_back(std::move(level));
  }
}

AmrexPlotfileWriter::~AmrexPlotfileWriter() {
  if (finished_) return;
  std::error_code ec;
  perLevel_.clear();
  fs::remove_all(partial_, ec); // never a half-written plotfile
}

namespace {

/// Each level's cells of the piece, leaves and covered, by exabricks level; a covered cell holds
/// the mean of its children, as AMReX's average-down makes it.
void averageDown(std::vector<PieceBoxes>& levels, const std::string& path) {
  const size_t nf = levels[0].fields;
  for (size_t l = 0; l + 1 < levels.size(); ++l) {
    PieceBoxes& fine = levels[l];
    PieceBoxes& coarse = levels[l + 1];
    const int64_t e = fine.edge;
    for (size_t b = 0; b < fine.boxes.size(); ++b) // by index: `coarse.at` does not touch `fine`
      for (int64_t z = 0; z < e; ++z)
        for (int64_t y = 0; y < e; ++y)
          for (int64_t x = 0; x < e; ++x) {
            const PieceBoxes::Box& box = fine.boxes[b];
            const size_t slot = size_t((z * e + y) * e + x);
            if (!box.present[slot]) continue;
            auto [parent, ps] = coarse.at((box.origin + vec3l(x, y, z)) / int64_t(2));
            ++parent->children[ps];
            for (size_t f = 0; f < nf; ++f)
              parent->values[ps * nf + f] += box.values[slot * nf + f];
          }
    for (PieceBoxes::Box& box : coarse.boxes)
      for (size_t s = 0; s < box.present.size(); ++s)
        if (box.children[s]) {
          if (box.present[s]) fail(path, ": a leaf cell of the piece has finer cells under it");
          if (box.children[s] != 8)
            fail(path, ": a cell is refined into ", int(box.children[s]),
                 " cells, not 8: data with holes (space without cells under a refined cell) cannot be a plotfile");
          box.present[s] = 1;
          for (size_t f = 0; f < nf; ++f)
            box.values[s * nf + f] /= float(box.children[s]);
        }
  }
}

/// Calls write(lower, cells, values) for the parts of the box within [0, hi) that hold cells: the
/// whole where every cell is there, else its two halves, each alike.
template <typename Write>
void boxesOf(const PieceBoxes::Box& box, int64_t e, size_t nf, const vec3l& hi, Write&& write) {
  auto count = [&](const vec3l& lo, const vec3l& up) {
    uint64_t k = 0;
    for (int64_t z = lo.z; z < up.z; ++z)
      for (int64_t y = lo.y; y < up.y; ++y)
        for (int64_t x = lo.x; x < up.x; ++x)
          k += box.present[size_t((z * e + y) * e + x)];
    return k;
  };
  auto emit = [&](auto&& self, const vec3l& lo, const vec3l& up) -> void {
    const vec3l ext = up - lo;
    const uint64_t k = count(lo, up);
    if (k == 0) return;
    if (k == uint64_t(ext.x * ext.y * ext.z)) {
      std::vector<float> values;
      values.reserve(size_t(k) * nf);
      for (size_t f = 0; f < nf; ++f)
        for (int64_t z = lo.z; z < up.z; ++z)
          for (int64_t y = lo.y; y < up.y; ++y)
            for (int64_t x = lo.x; x < up.x; ++x)
              values.push_back(box.values[size_t((z * e + y) * e + x) * nf + f]);
      write(box.origin + lo, ext, values);
      return;
    }
    // Halves along the longest axis, cut at an even cell where it can (every box then lies on
    // whole cells of the next coarser level, whose children come in aligned pairs).
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    const int64_t half = ext[axis] >= 4 ? (ext[axis] / 2) & ~int64_t(1) : ext[axis] / 2;
    vec3l cutHi = up, cutLo = lo;
    cutHi[axis] = cutLo[axis] = lo[axis] + half;
    self(self, lo, cutHi);
    self(self, cutLo, up);
  };
  emit(emit, vec3l(0), hi);
}

} // namespace

void AmrexPlotfileWriter::append(const CellSet& piece) {
  const size_t nf = names_.size();
  if (piece.fields.size() != nf) fail(path_, ": a piece holds ", piece.fields.size(), " fields, expected ", nf);
  std::vector<PieceBoxes> levels{size_t(levels_)}; // by exabricks level
  for (int l = 0; l < levels_; ++l) {
    levels[size_t(levels_ - 1 - l)].edge = perLevel_[size_t(l)]->edge;
    levels[size_t(levels_ - 1 - l)].fields = nf;
  }
  for (size_t i = 0; i < piece.cells.size(); ++i) {
    const Cell& c = piece.cells[i];
    if (c.level < 0 || c.level >= levels_ || c.lower.x < 0 || c.lower.y < 0 || c.lower.z < 0)
      fail(path_, ": cell ", i, " of a piece lies outside the plotfile's levels or lattice");
    auto [box, slot] = levels[size_t(c.level)].at(vec3l(c.lower.x, c.lower.y, c.lower.z) / (int64_t(1) << c.level));
    box->present[slot] = 1;
    for (size_t f = 0; f < nf; ++f)
      box->values[slot * nf + f] = piece.fields[f].values[i];
  }
  averageDown(levels, path_);
  // Every level's boxes in order (z, y, x), each cut where it holds cells only in part.
  for (int l = 0; l < levels_; ++l) {
    const PieceBoxes& pb = levels[size_t(levels_ - 1 - l)];
    std::map<std::tuple<int64_t, int64_t, int64_t>, size_t> order;
    for (size_t b = 0; b < pb.boxes.size(); ++b)
      order[{pb.boxes[b].origin.z, pb.boxes[b].origin.y, pb.boxes[b].origin.x}] = b;
    for (const auto& [key, b] : order) {
      const PieceBoxes::Box& box = pb.boxes[b];
      const vec3l hi = min(vec3l(pb.edge), vec3l(perLevel_[size_t(l)]->cells) - box.origin);
      boxesOf(box, pb.edge, nf, hi, [&](const vec3l& lower, const vec3l& cells, const std::vector<float>& values) {
        writeBox(l, lower, cells, values);
      });
    }
  }
}

void AmrexPlotfileWriter::writeBox(int l, const vec3l& lower, const vec3l& cells, const std::vector<float>& values) {
  Level& lv = *perLevel_[size_t(l)];
  if (!lv.data.is_open() || lv.written >= kFileBytes) {
    if (lv.data.is_open()) lv.data.close();
    char name[32];
    std::snprintf(name, sizeof name, "Cell_D_%05d", lv.fileCount++);
    lv.dataName = name;
    const fs::path file = fs::path(partial_) / ("Level_" + std::to_string(l)) / name;
    lv.data.open(file, std::ios::binary | std::ios::trunc);
    if (!lv.data) fail(file.string(), ": cannot create: ", std::strerror(errno));
    lv.written = 0;
  }
  const vec3l hi = lower + cells - vec3l(1);
  const size_t nf = names_.size(), n = values.size() / nf;
  std::string header =
      strCat("FAB ((8, (", float32_ ? "32 8 23 0 1 9 0 127" : "64 11 52 0 1 12 0 1023", ")),(",
             float32_ ? "4, (4 3 2 1)" : "8, (8 7 6 5 4 3 2 1)", "))", boxText(lower, hi), " ", nf, "\n");
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the FAB headers name little-endian data");
  lv.boxes.push_back({lower, hi});
  lv.files.push_back(lv.dataName);
  lv.offsets.push_back(lv.written);
  lv.data.write(header.data(), std::streamsize(header.size()));
  lv.written += header.size();
  for (size_t f = 0; f < nf; ++f) {
    const float* v = values.data() + f * n;
    const auto [lo, up] = std::minmax_element(v, v + n);
    lv.minima.push_back(*lo);
    lv.maxima.push_back(*up);
    if (float32_) {
      lv.data.write(reinterpret_cast<const char*>(v), std::streamsize(n * sizeof(float)));
      lv.written += n * sizeof(float);
    } else {
      std::vector<double> d(v, v + n);
      lv.data.write(reinterpret_cast<const char*>(d.data()), std::streamsize(n * sizeof(double)));
      lv.written += n * sizeof(double);
    }
  }
  if (!lv.data) fail(partial_, ": level ", l, ": cannot write the data (disk full?)");
}

uint64_t AmrexPlotfileWriter::finish() {
  const size_t nf = names_.size();
  uint64_t boxes = 0;
  for (int l = 0; l < levels_; ++l) {
    Level& lv = *perLevel_[size_t(l)];
    if (lv.data.is_open()) {
      lv.data.close();
      if (!lv.data) fail(partial_, ": level ", l, ": cannot write the data (disk full?)");
    }
    const fs::path cellH = fs::path(partial_) / ("Level_" + std::to_string(l)) / "Cell_H";
    std::ofstream h(cellH);
    h << "1\n0\n" << nf << "\n0\n(" << lv.boxes.size() << " 0\n";
    for (const auto& [lo, hi] : lv.boxes)
      h << boxText(lo, hi) << "\n";
    h << ")\n" << lv.boxes.size() << "\n";
    for (size_t b = 0; b < lv.boxes.size(); ++b)
      h << "FabOnDisk: " << lv.files[b] << " " << lv.offsets[b] << "\n";
    for (const std::vector<double>* table : {&lv.minima, &lv.maxima}) {
      h << "\n" << lv.boxes.size() << "," << nf << "\n";
      for (size_t b = 0; b < lv.boxes.size(); ++b) {
        for (size_t f = 0; f < nf; ++f)
          h << number((*table)[b * nf + f]) << ",";
        h << "\n";
      }
    }
    if (!h) fail(cellH.string(), ": cannot write");
    boxes += lv.boxes.size();
  }
  std::ofstream h(fs::path(partial_) / "Header");
  h << "HyperCLaw-V1.1\n" << nf << "\n";
  for (const std::string& n : names_)
    h << n << "\n";
  h << "3\n0\n" << levels_ - 1 << "\n0 0 0\n1 1 1\n";
  for (int l = 0; l + 1 < levels_; ++l)
    h << "2 ";
  h << "\n";
  for (int l = 0; l < levels_; ++l) {
    const int64_t n = perLevel_[size_t(l)]->cells;
    h << boxText(vec3l(0), vec3l(n - 1)) << " ";
  }
  h << "\n";
  for (int l = 0; l < levels_; ++l)
    h << "0 ";
  h << "\n";
  for (int l = 0; l < levels_; ++l) {
    const double dx = 1.0 / double(perLevel_[size_t(l)]->cells);
    h << number(dx) << " " << number(dx) << " " << number(dx) << "\n";
  }
  h << "0\n0\n";
  for (int l = 0; l < levels_; ++l) {
    const Level& lv = *perLevel_[size_t(l)];
    const double dx = 1.0 / double(lv.cells);
    h << l << " " << lv.boxes.size() << " 0\n0\n";
    for (const auto& [lo, hi] : lv.boxes)
      for (int a = 0; a < 3; ++a)
        h << number(double(lo[a]) * dx) << " " << number(double(hi[a] + 1) * dx) << "\n";
    h << "Level_" << l << "/Cell\n";
  }
  h.close();
  if (!h) fail(partial_, ": cannot write the Header");
  std::error_code ec;
  fs::remove_all(path_, ec);
  fs::rename(partial_, path_, ec);
  if (ec) fail(path_, ": cannot move the written plotfile into place: ", ec.message());
  finished_ = true;
  return boxes;
}

} // namespace exa
