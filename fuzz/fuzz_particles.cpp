// libFuzzer entry for the AMReX particle reader: the input holds a species' Header and the data
// files Level_0/DATA_00000 and Level_1/DATA_00000, cut at "--8<--" lines. The plotfile's own
// Header is a fixed valid one (a 4^3 domain over [0, 1]^3). The species is listed from its
// Header, then read whole and by name.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/particles.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = [] {
    fuzz::write("plt/Header", "HyperCLaw-V1.1\n1\nrho\n3\n0\n0\n0 0 0\n1 1 1\n\n((0,0,0) (3,3,3) (0,0,0))\n0\n"
                              "0.25 0.25 0.25\n0\n0\n0 1 0\n0\n0 1\n0 1\n0 1\nLevel_0/Cell\n");
    return true;
  }();
  (void)ready;
  const std::vector<std::string> p = fuzz::parts(data, size, 3);
  fuzz::write("plt/DM/Header", p[0]);
  fuzz::write("plt/DM/Level_0/DATA_00000", p[1]);
  fuzz::write("plt/DM/Level_1/DATA_00000", p[2]);
  const std::string dir = (fuzz::folder() / "plt").string();
  try {
    for (const exa::ParticleSpeciesInfo& s : exa::listAmrexParticles(dir))
      if (s.name != "DM") __builtin_trap();
    const exa::ParticleSet set = exa::readAmrexParticles(dir, "DM");
    for (const exa::ParticleSpecies& s : set.species)
      for (const exa::ParticleAttribute& a : s.attributes)
        if (a.values.size() != s.count()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
