// The machine profile chosen, loaded once per run, and its link settings applied.
#include "profile_choice.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

#include "exit_codes.h"

namespace hmc::cli {
namespace {

bool given(const CLI::Option* option) { return option != nullptr && option->count() > 0; }

// One run, one profile: loaded at its first use and kept (a motion file's may replace it).
std::optional<Result<const Profile*, int>> g_loaded;
std::optional<Profile> g_profile;

}  // namespace

Result<ProfileChoice> choose_profile(const GlobalOptions& o) { return find_profile(o.profile); }

int report_profile_error(const GlobalOptions& o, const ProfileError& error) {
  if (o.json) {
    nlohmann::json list = nlohmann::json::array();
    for (const ProfileMistake& m : error.mistakes) {
      list.push_back({{"file", error.path}, {"line", m.place.line}, {"column", m.place.column}, {"message", m.message}});
    }
    std::cout << nlohmann::json{{"errors", list}, {"syntax", error.syntax}} << '\n';
  } else {
    std::cerr << error.text();
    if (!error.unreadable) {
      std::cerr << error.mistakes.size() << (error.mistakes.size() == 1 ? " error" : " errors") << " in the profile"
                << (error.syntax ? " (a syntax error hides any after it)" : "") << "; nothing was sent\n";
    }
  }
  return error.unreadable ? kExitIo : kExitInvalid;
}

Result<const Profile*, int> use_profile(const GlobalOptions& o) {
  if (g_loaded) return *g_loaded;
  Result<ProfileChoice> choice = choose_profile(o);
  // No HOME and none named, or no default file: no profile.
  if (!choice || (!choice->exists && choice->from == "default")) {
    g_loaded = Result<const Profile*, int>(static_cast<const Profile*>(nullptr));
    return *g_loaded;
  }
  Result<Profile, ProfileError> read = load_profile(choice->path);
  if (!read) {
    g_loaded = Result<const Profile*, int>(report_profile_error(o, read.error()));
    return *g_loaded;
  }
  adopt_profile(std::move(*read));
  return *g_loaded;
}

void adopt_profile(Profile profile) {
  g_profile = std::move(profile);
  g_loaded = Result<const Profile*, int>(static_cast<const Profile*>(&*g_profile));
}

Result<GlobalOptions, int> with_profile_link(const GlobalOptions& o) {
  Result<const Profile*, int> p = use_profile(o);
  if (!p) return p.error();
  GlobalOptions out = o;
  if (*p == nullptr) return out;
  const Profile& profile = **p;
  if (!given(o.port_option) && profile.port) out.port = *profile.port;
  if (!given(o.baud_option) && profile.baud) out.baud = *profile.baud;
  if (!given(o.firmware_option) && profile.firmware) out.firmware = *profile.firmware;
  return out;
}

}  // namespace hmc::cli
