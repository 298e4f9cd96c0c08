// Saved positions: places a person names ("park", "start of shot") to send the axes back to.
// Each is the axes' positions in their own units (mm, deg; steps for a motor no profile axis
// drives), so that going back is an absolute move and rounding never adds up.
//
// They are kept in $XDG_STATE_HOME/hmc/positions.json (else ~/.local/state/hmc/positions.json),
// one list per machine profile (by its absolute path; "" without one). Not beside the profile:
// the profile is what the person writes and may keep under version control or read-only (the
// examples), while positions are what the program records as it is used — the XDG base
// directory specification's "state". A position means something only against the zero it was
// taken from, which a profile alone does not carry either.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "hmc/result.h"

namespace hmc::desk {

struct SavedPosition {
  std::string name;
  std::map<std::string, double> axes;  // axis name → position in its units
};

class SavedPositions {
 public:
  // The file's path from the environment; an error when neither XDG_STATE_HOME nor HOME is set.
  static Result<std::string> default_path();

  // The positions saved for `profile` in `path`; a missing file is an empty list.
  static Result<SavedPositions> load(const std::string& path, const std::string& profile);
  // Writes the file back (the other profiles' lists kept), creating its folder.
  Status save() const;

  const std::vector<SavedPosition>& list() const { return list_; }
  // Adds `position`, or replaces the one of the same name.
  void put(SavedPosition position);
  void remove(const std::string& name);

 private:
  std::string path_, profile_;
  std::vector<SavedPosition> list_;
};

}  // namespace hmc::desk
