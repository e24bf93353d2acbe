// Scene files: a JSON object whose keys are a command's long option names, so that every image
// can be reproduced from one file. `--write-scene` writes the options in effect.
#include "common.h"

#include "exabricks/io/native.h"

#include <fstream>
#include <sstream>

namespace exa::cli {
namespace {

/// CLI11 configuration in JSON: {"option": value, ...}; arrays give repeated or list values.
class JsonConfig : public CLI::Config {
public:
  explicit JsonConfig(std::string command) : command_(std::move(command)) {}

  std::string to_config(const CLI::App* app, bool defaultAlso, bool, std::string) const override {
    nlohmann::json j = nlohmann::json::object();
    for (const CLI::Option* opt : app->get_options()) {
      if (!opt->get_configurable()) continue;
      const std::string name = opt->get_single_name();
      if (name.empty() || name == "help" || name == "scene" || name == "write-scene") continue;
      std::vector<std::string> values = opt->results();
      if (values.empty() && defaultAlso && !opt->get_default_str().empty())
        values = {opt->get_default_str()};
      if (values.empty()) continue;
      auto encode = [](const std::string& v) -> nlohmann::json {
        try {
          size_t used = 0;
          const double d = std::stod(v, &used);
          if (used == v.size()) return d;
        } catch (...) {
        }
        if (v == "true") return true;
        if (v == "false") return false;
        return v;
      };
      if (opt->get_type_size_max() <= 1 && opt->get_expected_max() <= 1 && values.size() == 1)
        j[name] = encode(values[0]);
      else {
        nlohmann::json arr = nlohmann::json::array();
        for (const std::string& v : values) arr.push_back(encode(v));
        j[name] = arr;
      }
    }
    return j.dump(2) + "\n";
  }

  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    nlohmann::json j;
    try {
      input >> j;
    } catch (const nlohmann::json::exception& e) {
      throw CLI::ConversionError(std::string("scene file is not valid JSON: ") + e.what());
    }
    if (!j.is_object()) throw CLI::ConversionError("scene file must hold one JSON object");
    std::vector<CLI::ConfigItem> result;
    auto text = [](const nlohmann::json& v) -> std::string {
      if (v.is_string()) return v.get<std::string>();
      if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
      if (v.is_number_integer()) return std::to_string(v.get<long long>());
      if (v.is_number()) {
        std::ostringstream s;
        s.precision(17);
        s << v.get<double>();
        return s.str();
      }
      throw CLI::ConversionError("scene file values must be strings, numbers, booleans or arrays of them");
    };
    for (auto it = j.begin(); it != j.end(); ++it) {
      CLI::ConfigItem item;
      item.parents = {command_};
      item.name = it.key();
      if (it->is_array())
        for (const auto& v : *it) item.inputs.push_back(text(v));
      else
        item.inputs.push_back(text(*it));
      result.push_back(item);
    }
    return result;
  }

private:
  std::string command_; ///< the subcommand whose options the file holds
};

} // namespace

std::function<void()> addSceneFile(CLI::App& root, CLI::App& cmd) {
  // CLI11 reads configuration files at the top level only: the option lives on the root and
  // the subcommand lets it fall through, so `exabricks render --scene FILE` works. Options
  // given on the command line win over the file.
  const auto formatter = std::make_shared<JsonConfig>(cmd.get_name());
  root.config_formatter(formatter);
  cmd.config_formatter(formatter);
  root.set_config("--scene", "", "JSON file of options (keys are the long option names)");
  root.allow_config_extras(CLI::config_extras_mode::error);
  cmd.fallthrough();
  auto writeTo = std::make_shared<std::string>();
  cmd.add_option("--write-scene", *writeTo, "Write the options in effect to a JSON scene file")
      ->configurable(false);
  return [&cmd, writeTo] {
    if (writeTo->empty()) return;
    const std::string text = cmd.config_to_str(true, false);
    writeFileAtomic(*writeTo, text.data(), text.size());
  };
}

} // namespace exa::cli
