// What one region segment costs, piece by piece, on the rays of one view: the k-d walk alone,
// then the walk with a batch reconstruction (value and gradient) of every segment's samples,
// placed as the marcher places them at rate 1 (half the region's finest width apart). Every
// region counts as visible; one thread. It also counts the batches by their number of samples and
// the bricks they visit. Not a test: run by hand, e.g.
//   build-bench/bench/exabricks_bench_segments drop.model 512
#include "exabricks/accel/traversal.h"
#include "exabricks/amr/basis_batch.h"
#include "exabricks/io/model_file.h"
#include "exabricks/render/camera.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <vector>

using namespace exa;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MODEL [SIZE]\n", argv[0]);
    return 2;
  }
  const Model model = readModel(argv[1]);
  const int size = argc > 2 ? std::atoi(argv[2]) : 512;
  const RegionTraversal traversal(model, TraversalKind::KdTree);
  const FieldView view = model.view(0);
  const box3i cb = model.cellBounds();
  const Camera camera = Camera::frame(box3d(model.world.toWorld(vec3d(cb.lower)), model.world.toWorld(vec3d(cb.upper))),
                                      30, 20, 40, false);
  std::vector<Ray> rays;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      vec3d org, dir;
      camera.ray((x + 0.5) / size, (y + 0.5) / size, 1.0, org, dir);
      Ray r;
      r.org = vec3f(model.world.toLattice(org));
      r.dir = vec3f(normalize(dir / model.world.scale));
      rays.push_back(r);
    }
  std::printf("%s, %dx%d rays, one thread, best of 3\n", argv[1], size, size);
  for (const bool sample : {false, true}) {
    double best = 1e30;
    uint64_t segments = 0, samples = 0, batches = 0, brickVisits = 0;
    uint64_t bySize[kSampleBatch + 1] = {};
    float sink = 0.f;
    for (int round = 0; round < 3; ++round) {
      segments = samples = batches = brickVisits = 0;
      std::fill(std::begin(bySize), std::end(bySize), uint64_t(0));
      const auto start = std::chrono::steady_clock::now();
      for (const Ray& ray : rays)
        traversal.traverse(ray, [&](const Segment& s) {
          ++segments;
          if (!sample) return true;
          const float dt = 0.5f * model.regions.regions[s.region].finestWidth();
          SampleBatch batch;
          for (float a = s.t0; a < s.t1;) {
            batch.count = 0;
            for (; batch.count < kSampleBatch && a < s.t1; ++batch.count, a += dt) {
              const vec3f p = ray.org + ray.dir * std::min(a + 0.5f * dt, s.t1);
              batch.x[batch.count] = p.x, batch.y[batch.count] = p.y, batch.z[batch.count] = p.z;
            }
            samples += uint64_t(batch.count);
            ++batches, ++bySize[batch.count];
            brickVisits += model.regions.regions[s.region].brickCount;
            sampleRegionBatch(view, s.region, batch, true);
            sink += batch.value[0];
          }
          return true;
        });
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::printf("%-22s %8.3f s  %10llu segments  %6.1f ns/segment", sample ? "walk + batches" : "walk", best,
                static_cast<unsigned long long>(segments), best / double(segments) * 1e9);
    if (sample)
      std::printf("  %10llu samples  %5.1f ns/sample (%g)", static_cast<unsigned long long>(samples),
                  best / double(samples) * 1e9, double(sink));
    std::printf("\n");
    if (sample) {
      std::printf("batches %llu, %.2f samples and %.2f bricks each; batches by samples:",
                  static_cast<unsigned long long>(batches), double(samples) / double(batches),
                  double(brickVisits) / double(batches));
      for (int n = 1; n <= kSampleBatch; ++n)
        std::printf(" %d: %.1f%%", n, 100.0 * double(bySize[n]) / double(batches));
      std::printf("\n");
    }
  }
  return 0;
}
