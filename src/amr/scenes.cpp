#include "exabricks/amr/scenes.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace exa {
namespace {

/// SplitMix64: small, seedable, identical on every platform.
uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
double uniform(uint64_t& state) { return double((state = mix64(state)) >> 11) * 0x1.0p-53; }

/// An analytic scene over the unit cube: field values and the level wanted at a point.
struct Scene {
  std::vector<std::string> fieldNames;
  std::function<void(const vec3d& p, float* values)> evaluate;
  /// Finest level wanted anywhere in the box [lo, hi] (unit-cube coordinates), 0 .. maxLevel.
  std::function<int(const vec3d& lo, const vec3d& hi)> levelIn;
  /// Whether space at p is a hole (no cells).
  std::function<bool(const vec3d& p)> hole = [](const vec3d&) { return false; };
  /// Whether a cell refines straight to the wanted level (level jumps of more than one).
  bool jump = false;
  /// Refinement is decided per block of this many cells of a level per axis, as in
  /// block-structured AMR codes: a refined block becomes a patch of (2 block)^3 finer cells.
  int block = 4;
  /// Particles in unit-cube coordinates, `count` of the main species (null: the scene has none).
  std::function<ParticleSet(uint64_t count)> particles;
};

/// A standard normal deviate (Box-Muller).
double gaussian(uint64_t& state) {
  const double u = std::max(uniform(state), 0x1.0p-53), v = uniform(state);
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * M_PI * v);
}

/// Index of the first entry of an increasing cumulative sum above u.
size_t pick(const std::vector<double>& cumulative, double u) {
  const size_t i =
      size_t(std::upper_bound(cumulative.begin(), cumulative.end(), u * cumulative.back()) - cumulative.begin());
  return std::min(i, cumulative.size() - 1);
}

ParticleAttribute attribute(const std::string& name, size_t n, bool integer) {
  ParticleAttribute a;
  a.name = name;
  a.values.resize(n);
  a.integer = integer;
  return a;
}

Scene makeBlobs(uint64_t seed, int maxLevel, double time, double gridTime) {
  struct Blob {
    vec3d centre;
    double sigma, amplitude;
  };
  std::vector<Blob> blobs;
  uint64_t s = mix64(seed ^ 0xb10b5ull);
  for (int i = 0; i < 7; ++i) {
    Blob b;
    // One draw per statement: the order in which a call's arguments are evaluated is up to the
    // compiler, and the scene must be the same with any. (z, y, x: the order the datasets and
    // reference images were made with.)
    const double cz = uniform(s), cy = uniform(s), cx = uniform(s);
    b.centre = vec3d(0.2 + 0.6 * cx, 0.2 + 0.6 * cy, 0.2 + 0.6 * cz);
    b.sigma = 0.05 + 0.1 * uniform(s);
    b.amplitude = 0.4 + 0.6 * uniform(s);
    blobs.push_back(b);
  }
  // Motion for time series, from its own random stream (time 0 is the scene above). Each blob
  // drifts at 0.008 to 0.016 of the domain per unit of time.
  uint64_t m = mix64(seed ^ 0x7e10c17ull);
  std::vector<vec3d> velocity;
  for (size_t i = 0; i < blobs.size(); ++i) {
    const double vz = uniform(m) - 0.5, vy = uniform(m) - 0.5, vx = uniform(m) - 0.5;
    const double speed = 0.008 + 0.008 * uniform(m);
    velocity.push_back(normalize(vec3d(vx, vy, vz)) * speed);
  }
  std::vector<Blob> gridBlobs = blobs;
  for (size_t i = 0; i < blobs.size(); ++i) {
    blobs[i].centre = blobs[i].centre + velocity[i] * time;
    gridBlobs[i].centre = gridBlobs[i].centre + velocity[i] * (gridTime < 0 ? time : gridTime);
  }
  Scene scene;
  scene.fieldNames = {"scalar", "radius"};
  scene.evaluate = [blobs](const vec3d& p, float* v) {
    double f = 0;
    for (const Blob& b : blobs) {
      const vec3d d = p - b.centre;
      f += b.amplitude * std::exp(-dot(d, d) / (2 * b.sigma * b.sigma));
    }
    v[0] = float(f);
    v[1] = float(length(p - vec3d(0.5)));
  };
  auto levelAt = [gridBlobs, maxLevel](const vec3d& p) {
    // Refine where the field varies: the gradient magnitude relative to a typical maximum.
    vec3d g(0.0);
    for (const Blob& b : gridBlobs) {
      const vec3d d = p - b.centre;
      const double e = b.amplitude * std::exp(-dot(d, d) / (2 * b.sigma * b.sigma));
      g += d * (-e / (b.sigma * b.sigma));
    }
    const double t = std::min(1.0, length(g) / 6.0);
    return std::clamp(maxLevel - int(std::floor(t * (maxLevel + 1) * 1.3)), 0, maxLevel);
  };
  // The field is smooth at the scale of a block: corners and centre suffice.
  scene.levelIn = [levelAt](const vec3d& lo, const vec3d& hi) {
    int level = levelAt((lo + hi) * 0.5);
    for (int c = 0; c < 8 && level > 0; ++c)
      level = std::min(level, levelAt(vec3d(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z)));
    return level;
  };
  return scene;
}

Scene makeShells(uint64_t seed, int maxLevel) {
  uint64_t s = mix64(seed ^ 0x5e11ull);
  const double radius = 0.28 + 0.06 * uniform(s);
  const double frequency = 5.0 + 2.0 * uniform(s);
  Scene scene;
  scene.fieldNames = {"scalar", "radius"};
  scene.evaluate = [=](const vec3d& p, float* v) {
    const double r = length(p - vec3d(0.5));
    v[0] = float(0.5 + 0.5 * std::cos(2 * M_PI * frequency * r) * std::exp(-3 * r) + 0.2 * std::sin(6 * p.z));
    v[1] = float(r);
  };
  scene.levelIn = [=](const vec3d& lo, const vec3d& hi) {
    // Distance range from the centre over the box, against the shell band.
    const vec3d c(0.5);
    const vec3d nearest = max(lo, min(c, hi));
    vec3d farthest;
    for (int a = 0; a < 3; ++a)
      farthest[a] = std::abs(lo[a] - c[a]) > std::abs(hi[a] - c[a]) ? lo[a] : hi[a];
    const double dmin = length(nearest - c), dmax = length(farthest - c);
    auto touches = [&](double band) { return dmin < radius + band && dmax > radius - band; };
    // The finest level next to the coarsest: level jumps of more than one.
    if (touches(0.035)) return 0;
    if (touches(0.06) && hi.z > 0.5) return std::min(1, maxLevel);
    return maxLevel;
  };
  scene.hole = [](const vec3d& p) {
    const double r = length(p - vec3d(0.5));
    return r < 0.12 || r > 0.5 || (p.x > 0.6 && p.y > 0.6 && p.z < 0.4);
  };
  scene.jump = true;
  scene.block = 1;
  return scene;
}

Scene makeRamp(uint64_t seed, int maxLevel) {
  Scene scene;
  scene.fieldNames = {"scalar"};
  scene.evaluate = [](const vec3d& p, float* v) { v[0] = float(p.x + 2 * p.y + 3 * p.z); };
  // A random level per region of the unit cube, from a coarse hashed lattice.
  // A random level per block of a 4^3 lattice over the unit cube, taken at the box centre.
  scene.levelIn = [seed, maxLevel](const vec3d& lo, const vec3d& hi) {
    const vec3d c = (lo + hi) * 0.5;
    const vec3i q(int(std::floor(c.x * 4)), int(std::floor(c.y * 4)), int(std::floor(c.z * 4)));
    const uint64_t h =
        mix64(seed ^ mix64(uint64_t(q.x) * 73856093ull ^ uint64_t(q.y) * 19349663ull ^ uint64_t(q.z) * 83492791ull));
    return int(h % uint64_t(maxLevel + 1));
  };
  scene.jump = true;
  scene.block = 1;
  return scene;
}

/// A cosmology-like density: a log-normal field of periodic plane waves (amplitude falling with
/// wavenumber, as a power spectrum does), with compact haloes on top, spanning five to six
/// decades; cells refine by one level per factor of eight in overdensity, so the voids keep the
/// coarsest cells.
struct Wave {
  vec3d k;
  double amplitude, phase;
};
struct Halo {
  vec3d centre;
  double sigma, mass;
};

/// Dark matter where the cosmic density is (the web's share drawn from its log-normal part on a
/// 64^3 grid, each halo's share from its Gaussian), equal masses; stars (count / 25) in the
/// haloes, three times more concentrated, of 1 to 30 dark-matter masses, with creation times.
/// Species and attributes as exabricks names Enzo's: mass, index, type (1 dark matter,
/// 2 stars) and the stars' creation_time. Unit-cube coordinates.
ParticleSet cosmicParticles(const std::vector<Wave>& waves, const std::vector<Halo>& haloes, uint64_t seed,
                            uint64_t count) {
  constexpr int grid = 64;
  std::vector<double> web(size_t(grid) * grid * grid);
  tbb::parallel_for(0, grid, [&](int z) {
    for (int y = 0; y < grid; ++y)
      for (int x = 0; x < grid; ++x) {
        const vec3d p = (vec3d(x, y, z) + vec3d(0.5)) / double(grid);
        double d = 0;
        for (const Wave& w : waves)
          d += w.amplitude * std::cos(dot(w.k, p) + w.phase);
        web[(size_t(z) * grid + size_t(y)) * grid + size_t(x)] = std::exp(d - 1.28) / double(web.size());
      }
  });
  // One cumulative sum over the web's grid cells and then the haloes (mass (2 pi)^1.5 sigma^3 m).
  std::vector<double> all(web.size() + haloes.size()), stellar(haloes.size());
  double sum = 0;
  for (size_t i = 0; i < web.size(); ++i)
    all[i] = sum += web[i];
  double stars = 0;
  for (size_t h = 0; h < haloes.size(); ++h) {
    const double mass = std::pow(2 * M_PI, 1.5) * std::pow(haloes[h].sigma, 3) * haloes[h].mass;
    all[web.size() + h] = sum += mass;
    stellar[h] = stars += mass;
  }
  auto inHalo = [&](const Halo& h, double sigma, uint64_t& state) {
    vec3d p;
    for (int a = 0; a < 3; ++a) {
      const double x = h.centre[a] + sigma * gaussian(state);
      p[a] = x - std::floor(x); // periodic
    }
    return p;
  };
  ParticleSet set;
  const uint64_t starCount = count / 25;
  for (int kind = 1; kind <= 2; ++kind) {
    const size_t n = size_t(kind == 1 ? count : starCount);
    ParticleSpecies sp;
    sp.name = kind == 1 ? "dark_matter" : "star";
    sp.precision = "double";
    sp.position.resize(3 * n);
    sp.attributes = {attribute("mass", n, false), attribute("index", n, true), attribute("type", n, true)};
    if (kind == 2) sp.attributes.push_back(attribute("creation_time", n, false));
    const uint64_t first = kind == 1 ? 0 : count;
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
      uint64_t state = mix64(seed ^ mix64(0x9a271c1e5ull + first + i));
      vec3d p;
      if (kind == 1) {
        const size_t c = pick(all, uniform(state));
        if (c < web.size()) {
          const vec3d corner(double(c % grid), double(c / grid % grid), double(c / grid / grid));
          const double ux = uniform(state), uy = uniform(state), uz = uniform(state);
          p = (corner + vec3d(ux, uy, uz)) / double(grid);
        } else {
          p = inHalo(haloes[c - web.size()], haloes[c - web.size()].sigma, state);
        }
        sp.attributes[0].values[i] = sum / double(count);
      } else {
        const Halo& h = haloes[pick(stellar, uniform(state))];
        p = inHalo(h, h.sigma / 3, state);
        sp.attributes[0].values[i] = sum / double(count) * std::pow(10.0, 1.5 * uniform(state));
        sp.attributes[3].values[i] = uniform(state);
      }
      for (int a = 0; a < 3; ++a)
        sp.position[3 * i + size_t(a)] = p[a];
      sp.attributes[1].values[i] = double(first + i);
      sp.attributes[2].values[i] = kind;
    });
    set.species.push_back(std::move(sp));
  }
  return set;
}

Scene makeCosmic(uint64_t seed, int maxLevel) {
  uint64_t s = mix64(seed ^ 0xc05b1cull);
  std::vector<Wave> waves;
  double variance = 0;
  while (waves.size() < 32) {
    const double kz = std::floor(uniform(s) * 13) - 6, ky = std::floor(uniform(s) * 13) - 6,
                 kx = std::floor(uniform(s) * 13) - 6;
    const vec3d k(kx, ky, kz);
    const double kl = length(k);
    if (kl < 1.5) continue;
    const double phase = 2 * M_PI * uniform(s);
    waves.push_back({k * (2 * M_PI), std::pow(kl, -1.3), phase});
    variance += 0.5 * waves.back().amplitude * waves.back().amplitude;
  }
  const double norm = 1.6 / std::sqrt(variance); // standard deviation of ln(density)
  for (Wave& w : waves)
    w.amplitude *= norm;
  std::vector<Halo> haloes;
  for (int i = 0; i < 24; ++i) {
    const double cz = uniform(s), cy = uniform(s), cx = uniform(s);
    const double sigma = 0.006 + 0.014 * uniform(s);
    haloes.push_back({vec3d(cx, cy, cz), sigma, std::pow(10.0, 1.5 + 2.5 * uniform(s))});
  }
  auto density = [waves, haloes](const vec3d& p) {
    double d = 0;
    for (const Wave& w : waves)
      d += w.amplitude * std::cos(dot(w.k, p) + w.phase);
    double rho = std::exp(d - 1.28); // mean of the log-normal part near 1
    for (const Halo& h : haloes) {
      vec3d q = p - h.centre;
      for (int a = 0; a < 3; ++a)
        q[a] -= std::round(q[a]); // periodic
      const double r2 = dot(q, q) / (h.sigma * h.sigma);
      if (r2 < 40) rho += h.mass * std::exp(-0.5 * r2);
    }
    return rho;
  };
  Scene scene;
  scene.fieldNames = {"density"};
  scene.evaluate = [density](const vec3d& p, float* v) { v[0] = float(density(p)); };
  auto levelAt = [density, maxLevel](const vec3d& p) {
    const double rho = density(p);
    const int refinements = rho > 1.0 ? 1 + int(std::floor(std::log(rho) / std::log(8.0))) : 0;
    return std::clamp(maxLevel - refinements, 0, maxLevel);
  };
  scene.levelIn = [levelAt](const vec3d& lo, const vec3d& hi) {
    int level = levelAt((lo + hi) * 0.5);
    for (int c = 0; c < 8 && level > 0; ++c)
      level = std::min(level, levelAt(vec3d(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z)));
    return level;
  };
  scene.block = 2;
  scene.particles = [waves, haloes, seed](uint64_t count) { return cosmicParticles(waves, haloes, seed, count); };
  return scene;
}

Scene makeScene(const SceneOptions& o) {
  const int maxLevel = o.levels - 1;
  if (o.name == "blobs") return makeBlobs(o.seed, maxLevel, o.time, o.gridTime);
  if (o.time != 0 || o.gridTime >= 0) fail("scene '", o.name, "' does not change with time (only blobs moves)");
  if (o.name == "shells") return makeShells(o.seed, maxLevel);
  if (o.name == "ramp") return makeRamp(o.seed, maxLevel);
  if (o.name == "cosmic") return makeCosmic(o.seed, maxLevel);
  std::string known;
  for (const SceneInfo& s : sceneList())
    known += (known.empty() ? "" : ", ") + s.name;
  fail("unknown scene '", o.name, "' (scenes: ", known, ")");
}

struct Output {
  std::vector<Cell> cells;
  std::vector<std::vector<float>> values;
};

/// Emits the leaf cells of one base cell (or only counts them when `out` is null).
uint64_t refine(const Scene& scene, const vec3i& lower, int level, double unit, Output* out) {
  const int w = 1 << level;
  int wanted = level;
  if (level > 0) {
    const int bw = scene.block * w;
    const vec3i block(int(floorDiv(lower.x, bw)) * bw, int(floorDiv(lower.y, bw)) * bw,
                      int(floorDiv(lower.z, bw)) * bw);
    wanted = std::min(wanted, scene.levelIn(vec3d(block) * unit, (vec3d(block) + vec3d(bw)) * unit));
  }
  if (wanted < level) {
    const int childLevel = scene.jump ? wanted : level - 1;
    const int n = 1 << (level - childLevel), cw = 1 << childLevel;
    uint64_t count = 0;
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          count += refine(scene, lower + vec3i(x, y, z) * cw, childLevel, unit, out);
    return count;
  }
  const vec3d centre = (vec3d(lower) + vec3d(0.5 * w)) * unit;
  if (scene.hole(centre)) return 0;
  if (out) {
    out->cells.push_back(Cell{lower, level});
    float v[8];
    scene.evaluate(centre, v);
    for (size_t f = 0; f < out->values.size(); ++f)
      out->values[f].push_back(v[f]);
  }
  return 1;
}

uint64_t countCells(const Scene& scene, int base, int maxLevel) {
  const int w = 1 << maxLevel;
  const double unit = 1.0 / (double(base) * w);
  std::vector<uint64_t> perSlab(size_t(base), 0);
  tbb::parallel_for(0, base, [&](int z) {
    for (int y = 0; y < base; ++y)
      for (int x = 0; x < base; ++x)
        perSlab[size_t(z)] += refine(scene, vec3i(x, y, z) * w, maxLevel, unit, nullptr);
  });
  uint64_t n = 0;
  for (uint64_t c : perSlab)
    n += c;
  return n;
}

} // namespace

const std::vector<SceneInfo>& sceneList() {
  static const std::vector<SceneInfo> list = {
      {"blobs", "sum of Gaussian blobs, refined where the field varies; fields scalar, radius"},
      {"shells", "radial waves in a hollow ball with a cut-out; finest cells next to coarsest "
                 "(level jumps of more than one) and holes; fields scalar, radius"},
      {"ramp", "linear field x + 2y + 3z with random levels per block and level jumps"},
      {"cosmic", "cosmology-like density: log-normal web with haloes over five decades, refined by "
                 "overdensity (coarsest cells in the voids); field density"},
  };
  return list;
}

SceneOptions resolveSceneSize(const SceneOptions& o) {
  if (o.levels < 1 || o.levels > 12) fail("levels must be between 1 and 12, got ", o.levels);
  if (o.targetCells < 1 || o.targetCells > (uint64_t(1) << 32) - 1)
    fail("cell count must be between 1 and 2^32-1, got ", o.targetCells);
  Scene scene = makeScene(o);
  int maxLevel = o.levels - 1;
  // A request smaller than one refined base cell gets fewer levels.
  while (maxLevel > 0 && double(countCells(scene, 1, maxLevel)) > 2.0 * double(o.targetCells)) {
    --maxLevel;
    SceneOptions fewer = o;
    fewer.levels = maxLevel + 1;
    scene = makeScene(fewer);
    logInfo(strCat("scene ", o.name, ": using ", maxLevel + 1, " levels for ", o.targetCells, " cells"));
  }

  // The level map is fixed in unit-cube coordinates, so once blocks are small against the
  // features the count grows with the cube of the base resolution. Measure small bases
  // directly and extrapolate from the largest one measured.
  int base = 1;
  uint64_t count = countCells(scene, 1, maxLevel);
  double bestError = std::abs(std::log(double(std::max<uint64_t>(count, 1)) / double(o.targetCells)));
  for (int b = 2; count < o.targetCells && count < 400000; b = b < 8 ? b + 1 : b * 5 / 4) {
    count = countCells(scene, b, maxLevel);
    const double error = std::abs(std::log(double(std::max<uint64_t>(count, 1)) / double(o.targetCells)));
    if (error < bestError) {
      bestError = error;
      base = b;
    }
    if (count >= o.targetCells) break;
    if (count >= 400000 || b >= 2048) {
      // Extrapolate, count there (cheap: nothing is stored) and correct once.
      int guess = std::clamp(int(std::lround(b * std::cbrt(double(o.targetCells) / double(count)))), 1, 2048);
      const uint64_t guessCount = countCells(scene, guess, maxLevel);
      const double ratio = double(o.targetCells) / double(std::max<uint64_t>(guessCount, 1));
      base = int(std::lround(guess * std::cbrt(ratio)));
      break;
    }
  }
  base = std::clamp(base, 1, 2048);
  SceneOptions resolved = o;
  resolved.levels = maxLevel + 1;
  resolved.base = base;
  return resolved;
}

uint64_t generateScenePieces(const SceneOptions& options, int slabsPerPiece,
                             const std::function<void(CellSet&)>& consume) {
  const SceneOptions o = options.base > 0 ? options : resolveSceneSize(options);
  if (o.levels < 1 || o.levels > 12) fail("levels must be between 1 and 12, got ", o.levels);
  if (o.base < 1 || o.base > 2048) fail("base resolution must be between 1 and 2048, got ", o.base);
  const Scene scene = makeScene(o);
  const int maxLevel = o.levels - 1;
  const int w = 1 << maxLevel;
  const int base = o.base;
  if (uint64_t(base) * w > uint64_t(kLatticeLimit)) fail("requested size is too large");

  const double unit = 1.0 / (double(base) * w);
  const int batch = std::clamp(slabsPerPiece, 1, base);
  Progress progress("generating " + o.name, uint64_t(base));
  uint64_t total = 0;
  for (int z0 = 0; z0 < base; z0 += batch) {
    const int n = std::min(batch, base - z0);
    std::vector<Output> slabs(static_cast<size_t>(n));
    tbb::parallel_for(0, n, [&](int i) {
      Output& out = slabs[size_t(i)];
      out.values.resize(scene.fieldNames.size());
      for (int y = 0; y < base; ++y)
        for (int x = 0; x < base; ++x)
          refine(scene, vec3i(x, y, z0 + i) * w, maxLevel, unit, &out);
      progress.advance(1);
    });
    // The piece: the slabs in z order, each freed as it is appended.
    CellSet piece;
    size_t cells = 0;
    for (const Output& slab : slabs)
      cells += slab.cells.size();
    total += cells;
    if (total >= (uint64_t(1) << 32) - 1) fail("scene produced too many cells: more than ", total - 1);
    piece.cells.reserve(cells);
    piece.fields.resize(scene.fieldNames.size());
    for (size_t f = 0; f < scene.fieldNames.size(); ++f) {
      piece.fields[f].name = scene.fieldNames[f];
      piece.fields[f].values.reserve(cells);
    }
    for (Output& slab : slabs) {
      piece.cells.insert(piece.cells.end(), slab.cells.begin(), slab.cells.end());
      std::vector<Cell>().swap(slab.cells);
      for (size_t f = 0; f < slab.values.size(); ++f) {
        piece.fields[f].values.insert(piece.fields[f].values.end(), slab.values[f].begin(), slab.values[f].end());
        std::vector<float>().swap(slab.values[f]);
      }
    }
    consume(piece);
  }
  progress.finish();
  if (total == 0) fail("scene '", o.name, "' produced no cells at this size");
  return total;
}

CellSet generateScene(const SceneOptions& options) {
  // One piece holding every slab.
  CellSet set;
  generateScenePieces(options, std::numeric_limits<int>::max(), [&](CellSet& piece) { set = std::move(piece); });
  return set;
}

bool sceneHasParticles(const SceneOptions& options) { return bool(makeScene(options).particles); }

double sceneLatticeWidth(const SceneOptions& resolved) {
  return double(resolved.base) * double(1 << (resolved.levels - 1));
}

ParticleSet generateSceneParticles(const SceneOptions& options, uint64_t count) {
  const SceneOptions o = options.base > 0 ? options : resolveSceneSize(options);
  const Scene scene = makeScene(o);
  if (!scene.particles) fail("scene '", o.name, "' has no particles (cosmic has)");
  if (count > (uint64_t(1) << 32)) fail("at most 2^32 particles, asked for ", count);
  ParticleSet set = scene.particles(count);
  // Unit-cube coordinates to the lattice's (the world of a native dataset).
  const double width = sceneLatticeWidth(o);
  for (ParticleSpecies& sp : set.species)
    for (double& x : sp.position)
      x *= width;
  return set;
}

CellSet defaultDataset() { return generateScene(SceneOptions{}); }

} // namespace exa
