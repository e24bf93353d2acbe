// Time series on disk: the inputs of a movie, from files, directories and glob patterns, in
// numeric order (plt200 before plt1000).
#pragma once

#include <string>
#include <vector>

namespace exa {

/// Compares names with runs of digits compared as numbers ("plt200" < "plt1000"); ties fall back
/// to plain comparison.
bool naturalLess(const std::string& a, const std::string& b);

/// The datasets the inputs name, in numeric order without duplicates: a file or a dataset
/// directory (an AMReX plotfile) as itself, a glob pattern (* ? [...]) as its matches, another
/// directory as the datasets directly inside it (companion files such as NAME.scalars are not
/// datasets). Throws exa::Error naming an input that matches nothing.
std::vector<std::string> expandSeries(const std::vector<std::string>& inputs);

} // namespace exa
