#include "core/config.h"
#include "core/config_check.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

#include "core/file_text.h"
#include "core/json_input.h"

#include <toml++/toml.h>

namespace doasido {
namespace {

Json TomlToJson(const toml::node& node) {
  if (const auto* table = node.as_table()) {
    Json out = Json::object();
    for (const auto& [key, value] : *table) out[std::string(key.str())] = TomlToJson(value);
    return out;
  }
  if (const auto* array = node.as_array()) {
    Json out = Json::array();
    for (const auto& value : *array) out.push_back(TomlToJson(value));
    return out;
  }
  if (const auto* v = node.as_string()) return v->get();
  if (const auto* v = node.as_integer()) return v->get();
  if (const auto* v = node.as_floating_point()) return v->get();
  if (const auto* v = node.as_boolean()) return v->get();
  throw Error("bad_config", "dates and times are not valid parameter values");
}

}  // namespace

Json LoadConfigFile(const std::filesystem::path& path) {
  const std::string text = ReadFileOrThrow(path, "bad_config", "cannot open config file");
  if (path.extension() == ".json") {
    try {
      return ParseJsonInput(text, {.file = path.string()}, {.max_bytes = 16u << 20});
    } catch (const Error& e) {
      throw Error("bad_config", e.message(), e.site());
    }
  }
  try {
    return TomlToJson(toml::parse(text, path.string()));
  } catch (const toml::parse_error& e) {
    throw Error("bad_config", std::string(e.description()),
                {.file = path.string(), .line = static_cast<long>(e.source().begin.line)});
  }
}

void RequireInRange(const std::string& section, const std::string& key, double value, double lo,
                    double hi) {
  if (value >= lo && value <= hi) return;
  std::ostringstream message;
  message << "value " << value << " is out of range [" << lo << ", " << hi << "]";
  throw Error("bad_config", message.str(), {.field = section + "." + key});
}

void RequireOneOf(const std::string& section, const std::string& key, const std::string& value,
                  const std::vector<std::string>& choices) {
  std::string list;
  for (const auto& choice : choices) {
    if (choice == value) return;
    list += (list.empty() ? "\"" : ", \"") + choice + "\"";
  }
  throw Error("bad_config", "value \"" + value + "\" is not one of " + list,
              {.field = section + "." + key});
}

void RequireSameShape(const std::string& section, const Json& defaults, const Json& given) {
  if (!defaults.is_object() || !given.is_object()) return;  // ReadSection names these
  for (const auto& item : given.items()) {
    const std::string& key = item.key();
    const Json& value = item.value();  // a plain reference: lambdas below capture it
    const std::string field = section + "." + key;
    if (!defaults.contains(key)) throw Error("bad_config", "unknown key", {.field = field});
    const Json& def = defaults.at(key);
    auto refuse = [&](const std::string& expected) {
      throw Error("bad_config", "expects " + expected + ", got " + value.dump(),
                  {.field = field});
    };
    if (def.is_object()) {
      if (!value.is_object()) refuse("a table");
      RequireSameShape(field, def, value);
    } else if (def.is_boolean() && !value.is_boolean()) {
      refuse("true or false");
    } else if (def.is_string() && !value.is_string()) {
      refuse("a string");
    } else if (def.is_array() && !value.is_array()) {
      refuse("an array");
    } else if (def.is_number()) {
      if (!value.is_number()) refuse("a number");
      if (def.is_number_integer() && value.is_number_float()) {
        // Converting a double past int's range to int is undefined
        // behaviour (found by hand_import_fuzz in a hand description).
        const double v = value.get<double>();
        if (!std::isfinite(v) || std::trunc(v) != v) refuse("an integer");
        if (std::abs(v) > 2147483647.0) refuse("an integer within +-2147483647");
      }
      if (def.is_number_unsigned() && value.is_number_integer() && value.get<long long>() < 0) {
        refuse("a non-negative integer");
      }
    }
  }
}

std::string ParamHash(const Json& params) {
  const std::string text = params.dump();
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace doasido
