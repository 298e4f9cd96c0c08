// ScriptDriver: the test mode (--script). It plays a small script against the panel's own
// widgets, one frame at a time: a click is a pending click on a widget's key that the panel
// honours when it draws that widget, so the test goes through the same code as a mouse.
//
// Widget keys are the visible label, prefixed by the group when it repeats: "Connect",
// "STOP ALL", "motor 1/+100", "motor 3/Move", "LED 1/Apply", "file/Run".
//
// Script lines ('#' starts a comment):
//   connect | disconnect              click Connect / Disconnect
//   wait MS                           let the panel run MS milliseconds
//   wait-for connected|idle [MS]      until the board is connected / nothing moves or is queued
//   click "KEY"   press KEY           click a button (press takes the rest of the line: press STOP ALL)
//   hold "KEY"    release "KEY"       hold a button down / let it go: hold "motor 2/hold fwd >>"
//   set "KEY" V...                    put values into an input (steps, speed, colour ...)
//   jog M +N                          click motor M's jog button +N (or -N)
//   move M STEPS                      type STEPS into motor M's move field and click Move
//   led S R G B W                     set strip S's colour and click Apply
//   servo S ANGLE                     set servo S's slider
//   open PATH    run                  open a motion file / run it
//   text "KEY" TEXT                   put TEXT into a text field: text "motor 1/go to" 250mm
//   key NAME                          a key pressed and let go: Right, Left, Up, Down, PageUp,
//                                     PageDown (shift+Right ...), or a character: + - z space
//   stick LX|LY|RX|RY VALUE           the scripted gamepad's stick (-1..1; Y down positive, as GLFW)
//   button A|B down|up                its buttons
//   gamepad absent                    unplugs it (a stick or button line plugs it in)
//   focus lost|back                   the window loses / gets back the keyboard focus
//   hang MS                           the panel draws nothing for MS milliseconds (a stuck window)
//   expect-log "TEXT"                 some line of the event log holds TEXT (within 3 s)
//   screenshot NAME                   NAME.png in the screenshot directory
//   quit
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "board_worker.h"
#include "gamepad.h"

namespace hmc::desk {

class ScriptDriver {
 public:
  // Reads the script; an unreadable file or an unknown line is an error in `error`.
  bool load(const std::string& path, std::string& error);

  // Once a frame, before the panel draws: runs lines until one has to wait.
  void advance(double now_s, const Snapshot& snapshot);
  // The panel, drawing the widget `key`: true when the script clicks it now.
  bool take_click(const std::string& key);
  bool held(const std::string& key) const { return held_.count(key) != 0; }
  // The panel, drawing an input `key`: the values the script puts into it, once.
  std::optional<std::vector<double>> take_values(const std::string& key);
  std::optional<std::string> take_text(const std::string& key);
  // Before the frame: a key to press now ("Right", "shift+PageUp", "+"), once.
  std::optional<std::string> take_key();
  GamepadSource& gamepad() { return pad_; }
  bool focused() const { return focused_; }
  // After the frame is drawn: the name of a screenshot to take now, once.
  std::optional<std::string> take_screenshot();

  bool finished() const { return finished_; }
  const std::vector<std::string>& failures() const { return failures_; }

 private:
  struct Line {
    int number = 0;
    std::vector<std::string> words;  // quotes removed
  };
  // Runs one line; false when the script must wait a frame (or more) before going on.
  bool run(const Line& line, double now_s, const Snapshot& snapshot);
  void fail(const std::string& message);

  std::vector<Line> lines_;
  size_t next_ = 0;
  bool finished_ = false;
  std::vector<std::string> failures_;
  // The line in progress
  bool started_ = false;
  double started_s_ = 0;
  int frames_ = 0;
  std::optional<std::string> click_;
  std::optional<std::string> screenshot_;
  std::optional<std::string> key_;
  ScriptedGamepad pad_;
  bool focused_ = true;
  std::set<std::string> held_;
  std::map<std::string, std::vector<double>> values_;
  std::map<std::string, std::string> texts_;
};

}  // namespace hmc::desk
