#include "exabricks/io/units.h"

#include <algorithm>
#include <cctype>
#include <utility>

namespace exa {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

/// FLASH's variable names (four characters) and their CGS units.
std::string flashUnits(const std::string& name) {
  static const std::pair<const char*, const char*> table[] = {
      {"dens", "g/cm^3"},   {"temp", "K"},      {"tele", "K"},    {"tion", "K"},    {"trad", "K"},
      {"pres", "erg/cm^3"}, {"velx", "cm/s"},   {"vely", "cm/s"}, {"velz", "cm/s"}, {"ener", "erg/g"},
      {"eint", "erg/g"},    {"gpot", "erg/g"},  {"magx", "G"},    {"magy", "G"},    {"magz", "G"},
      {"magp", "erg/cm^3"}, {"pden", "g/cm^3"}, {"divb", "G/cm"}};
  for (const auto& [key, units] : table)
    if (name == key) return units;
  return "";
}

/// Enzo's field labels: temperature in kelvin; densities, energies and velocities in code units.
std::string enzoUnits(const std::string& name) {
  if (name == "Temperature" || name == "Dust_Temperature") return "K";
  const std::string l = lower(name);
  for (const char* coded : {"density", "energy", "velocity", "bfield", "potential"})
    if (l.find(coded) != std::string::npos) return "code units";
  return "";
}

} // namespace

std::string conventionalUnits(InputKind kind, const std::string& field) {
  switch (kind) {
  case InputKind::Flash:
    return flashUnits(field);
  case InputKind::Enzo:
    return enzoUnits(field);
  default:
    return "";
  }
}

void assignConventionalUnits(InputKind kind, CellSet& set) {
  for (Field& f : set.fields)
    if (f.units.empty()) f.units = conventionalUnits(kind, f.name);
}

} // namespace exa
