// Which machine profile a run uses, loaded once, and what the command line takes from it: the
// port, baud and firmware kind when the command line does not give them, and axes by name.
#pragma once

#include <string>

#include "connection.h"
#include "hmc/axis_moves.h"
#include "hmc/profile.h"

namespace hmc::cli {

using ProfileChoice = ProfileSource;

// --profile, else HMC_PROFILE, else the default path ($XDG_CONFIG_HOME/hmc/config.toml): libhmc's find_profile.
Result<ProfileChoice> choose_profile(const GlobalOptions& options);

// The profile in use, loaded and checked on first use: nullptr when none is named and the
// default file does not exist. A profile named but missing, or with mistakes, prints them (JSON
// with --json) and gives the exit code: nothing is sent to a board.
Result<const Profile*, int> use_profile(const GlobalOptions& options);

// A motion file's own profile becomes the one in use for the rest of the run (the port, baud and
// firmware it gives, the soft limits sent when the session opens). Motion files that name
// another profile than one chosen with --profile or HMC_PROFILE are refused before this.
void adopt_profile(Profile profile);

// Prints a profile's mistakes ("file:line:col: message", then the count) and returns the exit code.
int report_profile_error(const GlobalOptions& options, const ProfileError& error);

// The global options with the port, baud and firmware the profile gives where the command line
// (or HMC_PORT) gave none.
Result<GlobalOptions, int> with_profile_link(const GlobalOptions& options);

// number_text(), a number for people ("250", "26.667"), is libhmc's: hmc/axis_moves.h.

}  // namespace hmc::cli
