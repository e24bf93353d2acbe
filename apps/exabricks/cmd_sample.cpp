// exabricks sample: reconstructed values and gradients at given world positions.
#include "commands.h"
#include "common.h"

#include "exabricks/core/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

namespace exa::cli {
namespace {

struct SampleOptions {
  InputOptions in;
  std::string points; ///< empty or "-": standard input
};

void run(const SampleOptions& o) {
  const Model model = loadModel(o.in.input, o.in.loadOptions(true));
  const int field = model.requireField(o.in.field);

  std::ifstream file;
  std::istream* in = &std::cin;
  const std::string source = o.points.empty() || o.points == "-" ? "<stdin>" : o.points;
  if (source != "<stdin>") {
    file.open(o.points);
    if (!file) fail(o.points, ": cannot open: ", std::strerror(errno));
    in = &file;
  }
  std::string line, out;
  size_t lineNo = 0;
  char buffer[160];
  while (std::getline(*in, line)) {
    ++lineNo;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    double w[3];
    if (!(ls >> w[0])) continue; // blank or comment line
    std::string rest;
    if (!(ls >> w[1] >> w[2]) || (ls >> rest))
      fail(source, ": line ", lineNo, ": expected three numbers 'x y z'");
    double value;
    vec3d g;
    if (model.sampleWorld(field, vec3d(w[0], w[1], w[2]), value, g)) {
      std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g %.9g\n", value, g.x, g.y, g.z);
      out += buffer;
    } else {
      out += "nan nan nan nan\n";
    }
    if (out.size() > (1 << 16)) {
      std::fwrite(out.data(), 1, out.size(), stdout);
      out.clear();
    }
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
}

} // namespace

void addSample(CLI::App& app) {
  auto opts = std::make_shared<SampleOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sample", "Reconstruct 'value gx gy gz' at 'x y z' world positions (nan outside the data)");
  opts->in.add(*cmd);
  cmd->add_option("-p,--points", opts->points, "File of 'x y z' lines (default: standard input)");
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
