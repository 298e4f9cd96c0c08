// Saved positions in a JSON file (see saved_positions.h).
#include "saved_positions.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <sys/stat.h>

#include <nlohmann/json.hpp>

namespace hmc::desk {
namespace {

// Creates every folder of `path` that is missing, as `mkdir -p`.
Status make_folders(const std::string& path) {
  for (size_t slash = path.find('/', 1); slash != std::string::npos; slash = path.find('/', slash + 1)) {
    const std::string folder = path.substr(0, slash);
    if (mkdir(folder.c_str(), 0755) != 0 && errno != EEXIST) {
      return Error{"cannot create " + folder + ": " + std::strerror(errno)};
    }
  }
  return Done{};
}

Result<nlohmann::json> read_document(const std::string& path) {
  std::ifstream in(path);
  if (!in) return nlohmann::json::object();  // nothing saved yet
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return Error{path + ": not a saved-positions file (a JSON object)"};
  return doc;
}

}  // namespace

Result<std::string> SavedPositions::default_path() {
  const char* state = std::getenv("XDG_STATE_HOME");
  if (state != nullptr && state[0] == '/') return std::string(state) + "/hmc/positions.json";
  const char* home = std::getenv("HOME");
  if (home == nullptr || home[0] == '\0') return Error{"neither XDG_STATE_HOME nor HOME is set: positions cannot be saved"};
  return std::string(home) + "/.local/state/hmc/positions.json";
}

Result<SavedPositions> SavedPositions::load(const std::string& path, const std::string& profile) {
  Result<nlohmann::json> doc = read_document(path);
  if (!doc) return doc.error();
  SavedPositions out;
  out.path_ = path;
  out.profile_ = profile;
  const nlohmann::json& profiles = (*doc)["profiles"];
  if (!profiles.is_object() || !profiles.contains(profile)) return out;
  const nlohmann::json& list = profiles[profile];
  if (!list.is_array()) return Error{path + ": the positions of '" + profile + "' are not a list"};
  for (const nlohmann::json& entry : list) {
    if (!entry.is_object() || !entry.value("name", nlohmann::json()).is_string() || !entry.value("axes", nlohmann::json()).is_object()) {
      return Error{path + ": a position of '" + profile + "' is not {\"name\": ..., \"axes\": {...}}"};
    }
    SavedPosition p{entry["name"].get<std::string>(), {}};
    for (const auto& [axis, value] : entry["axes"].items()) {
      if (!value.is_number()) return Error{path + ": position '" + p.name + "', axis '" + axis + "' is not a number"};
      p.axes[axis] = value.get<double>();
    }
    out.list_.push_back(std::move(p));
  }
  return out;
}

Status SavedPositions::save() const {
  Result<nlohmann::json> doc = read_document(path_);  // keeps the other profiles' lists
  if (!doc) return doc.error();
  nlohmann::json list = nlohmann::json::array();
  for (const SavedPosition& p : list_) list.push_back({{"name", p.name}, {"axes", p.axes}});
  (*doc)["profiles"][profile_] = list;
  if (Status made = make_folders(path_); !made) return made;
  const std::string temporary = path_ + ".new";
  {
    std::ofstream out(temporary);
    out << doc->dump(2) << '\n';
    if (!out) return Error{"cannot write " + temporary};
  }
  if (std::rename(temporary.c_str(), path_.c_str()) != 0) return Error{"cannot replace " + path_ + ": " + std::strerror(errno)};
  return Done{};
}

void SavedPositions::put(SavedPosition position) {
  for (SavedPosition& p : list_) {
    if (p.name == position.name) {
      p = std::move(position);
      return;
    }
  }
  list_.push_back(std::move(position));
}

void SavedPositions::remove(const std::string& name) {
  for (auto it = list_.begin(); it != list_.end(); ++it) {
    if (it->name == name) {
      list_.erase(it);
      return;
    }
  }
}

}  // namespace hmc::desk
