// Saved positions (saved_positions.h): kept per profile, written back without losing the others.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>
#include <string>
#include <unistd.h>

#include "saved_positions.h"

namespace hmc::desk {
namespace {

std::string temporary_folder() {
  char name[] = "/tmp/hmc-positions-XXXXXX";
  REQUIRE(mkdtemp(name) != nullptr);
  return name;
}

TEST_CASE("positions are saved per profile, replaced by name, and read back") {
  const std::string file = temporary_folder() + "/state/hmc/positions.json";
  Result<SavedPositions> slider = SavedPositions::load(file, "/rigs/slider.toml");
  REQUIRE(slider);
  CHECK(slider->list().empty());  // nothing saved yet
  slider->put({"start", {{"slide", 12.5}}});
  slider->put({"end", {{"slide", 250}}});
  slider->put({"start", {{"slide", 10}}});  // the same name: replaced
  REQUIRE(slider->save());                  // the folders are made
  Result<SavedPositions> head = SavedPositions::load(file, "/rigs/head.toml");
  REQUIRE(head);
  head->put({"park", {{"pan", -90}, {"tilt", 0}, {"motor 3", 1600}}});
  REQUIRE(head->save());

  Result<SavedPositions> again = SavedPositions::load(file, "/rigs/slider.toml");
  REQUIRE(again);
  REQUIRE(again->list().size() == 2);
  CHECK(again->list()[0].name == "start");
  CHECK(again->list()[0].axes.at("slide") == 10);
  CHECK(again->list()[1].axes.at("slide") == 250);
  again->remove("start");
  REQUIRE(again->save());
  CHECK(SavedPositions::load(file, "/rigs/slider.toml")->list().size() == 1);
  CHECK(SavedPositions::load(file, "/rigs/head.toml")->list()[0].axes.at("motor 3") == 1600);
}

TEST_CASE("a damaged file is an error naming it, not an empty list that would overwrite it") {
  const std::string file = temporary_folder() + "/positions.json";
  std::ofstream(file) << "{\"profiles\": {\"\": [{\"name\": \"x\", \"axes\": {\"pan\": \"far\"}}]}}";
  Result<SavedPositions> read = SavedPositions::load(file, "");
  REQUIRE_FALSE(read);
  CHECK(read.error().message == file + ": position 'x', axis 'pan' is not a number");
  std::ofstream(file) << "not json";
  REQUIRE_FALSE(SavedPositions::load(file, ""));
}

TEST_CASE("the file is in XDG_STATE_HOME, else in ~/.local/state") {
  setenv("XDG_STATE_HOME", "/x/state", 1);
  CHECK(*SavedPositions::default_path() == "/x/state/hmc/positions.json");
  unsetenv("XDG_STATE_HOME");
  setenv("HOME", "/home/u", 1);
  CHECK(*SavedPositions::default_path() == "/home/u/.local/state/hmc/positions.json");
}

}  // namespace
}  // namespace hmc::desk
