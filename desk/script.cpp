// ScriptDriver: parses the test script and steps it frame by frame (see script.h).
#include "script.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

namespace hmc::desk {
namespace {

constexpr int kClickFrames = 60;  // a click no widget takes within this many frames fails

// Splits on blanks, keeping "quoted words" whole.
std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> words;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i >= text.size() || text[i] == '#') break;
    std::string word;
    if (text[i] == '"') {
      const size_t end = text.find('"', i + 1);
      word = text.substr(i + 1, end == std::string::npos ? std::string::npos : end - i - 1);
      i = end == std::string::npos ? text.size() : end + 1;
    } else {
      while (i < text.size() && text[i] != ' ' && text[i] != '\t') word += text[i++];
    }
    words.push_back(word);
  }
  return words;
}

bool number(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && end != nullptr && *end == '\0';
}

}  // namespace

bool ScriptDriver::load(const std::string& path, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot be read";
    return false;
  }
  static const std::set<std::string> known{"connect", "disconnect", "wait", "wait-for", "click", "press", "hold",
                                           "release", "set", "jog", "move", "led", "servo", "open", "run",
                                           "screenshot", "quit", "text", "key", "stick", "button", "gamepad",
                                           "focus", "hang", "expect-log"};
  std::string text;
  int line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    std::vector<std::string> words = split(text);
    if (words.empty()) continue;
    if (known.count(words[0]) == 0) {
      error = path + ":" + std::to_string(line_number) + ": unknown command '" + words[0] + "'";
      return false;
    }
    lines_.push_back(Line{line_number, std::move(words)});
  }
  return true;
}

void ScriptDriver::fail(const std::string& message) {
  const std::string text = "script line " + std::to_string(lines_[next_].number) + ": " + message;
  std::fprintf(stderr, "hmc-desk: %s\n", text.c_str());
  failures_.push_back(text);
}

void ScriptDriver::advance(double now_s, const Snapshot& snapshot) {
  while (!finished_ && next_ < lines_.size()) {
    if (!started_) {
      started_ = true;
      started_s_ = now_s;
      frames_ = 0;
    } else {
      ++frames_;
    }
    if (!run(lines_[next_], now_s, snapshot)) return;
    started_ = false;
    ++next_;
  }
  if (next_ >= lines_.size()) finished_ = true;
}

bool ScriptDriver::run(const Line& line, double now_s, const Snapshot& snapshot) {
  const std::vector<std::string>& w = line.words;
  const std::string& op = w[0];
  auto arg = [&](size_t i) { return i < w.size() ? w[i] : std::string(); };
  // A click waits until the widget takes it, then for one more frame to pass.
  auto click = [&](const std::string& key) {
    if (frames_ == 0) {
      click_ = key;
      return false;
    }
    if (!click_) return true;
    if (frames_ > kClickFrames) {
      fail("no widget \"" + key + "\" took the click");
      click_.reset();
      return true;
    }
    return false;
  };
  auto values = [&](const std::string& key, size_t from) {
    std::vector<double> v;
    for (size_t i = from; i < w.size(); ++i) {
      double x = 0;
      if (!number(w[i], x)) fail("'" + w[i] + "' is not a number");
      v.push_back(x);
    }
    values_[key] = v;
  };

  if (op == "connect") return click("Connect");
  if (op == "disconnect") return click("Disconnect");
  if (op == "click") return click(arg(1));
  if (op == "press") {
    std::string key;
    for (size_t i = 1; i < w.size(); ++i) key += (i > 1 ? " " : "") + w[i];
    return click(key);
  }
  if (op == "hold") {
    held_.insert(arg(1));
    return frames_ > 0;
  }
  if (op == "release") {
    held_.erase(arg(1));
    return frames_ > 0;
  }
  if (op == "set") {
    if (frames_ == 0) values(arg(1), 2);
    return true;
  }
  if (op == "jog") return click("motor " + arg(1) + "/" + arg(2));
  if (op == "move") {
    if (frames_ == 0) values("motor " + arg(1) + "/steps", 2);
    return click("motor " + arg(1) + "/Move");
  }
  if (op == "led") {
    if (frames_ == 0) values("LED " + arg(1) + "/colour", 2);
    return click("LED " + arg(1) + "/Apply");
  }
  if (op == "servo") {
    if (frames_ == 0) values("servo " + arg(1) + "/angle", 2);
    return frames_ > 1;
  }
  if (op == "open") {
    if (frames_ == 0) texts_["file/path"] = arg(1);
    return click("file/Open");
  }
  if (op == "run") return click("file/Run");
  if (op == "wait") {
    double ms = 0;
    if (!number(arg(1), ms)) fail("wait takes milliseconds");
    return now_s - started_s_ >= ms / 1000.0;
  }
  if (op == "wait-for") {
    double ms = 10000;
    if (!arg(2).empty() && !number(arg(2), ms)) fail("wait-for takes milliseconds");
    bool reached = false;
    if (arg(1) == "connected") {
      reached = snapshot.link == LinkState::kConnected;
    } else if (arg(1) == "idle") {
      reached = !snapshot.busy && !snapshot.running && !snapshot.model.any_moving();
    } else {
      fail("wait-for takes connected or idle");
      return true;
    }
    if (reached) return true;
    if (now_s - started_s_ >= ms / 1000.0) {
      fail("still not " + arg(1) + " after " + arg(2) + " ms");
      return true;
    }
    return false;
  }
  if (op == "text") {
    if (frames_ == 0) texts_[arg(1)] = arg(2);
    return frames_ > 1;
  }
  if (op == "key") {
    // Pressed in one frame, let go in the next, and one frame more so that the same key again is
    // a new press.
    if (frames_ == 0) key_ = arg(1);
    return frames_ > 2 && !key_;
  }
  if (op == "stick" || op == "button" || op == "gamepad") {
    if (frames_ > 0) return frames_ > 1;  // one frame for the panel to read it
    GamepadState& pad = pad_.state();
    pad.present = op != "gamepad" || arg(1) != "absent";
    if (op == "stick") {
      static const std::map<std::string, size_t> kSticks{{"LX", GamepadState::kLeftX}, {"LY", GamepadState::kLeftY},
                                                         {"RX", GamepadState::kRightX}, {"RY", GamepadState::kRightY}};
      double value = 0;
      if (kSticks.count(arg(1)) == 0 || !number(arg(2), value)) {
        fail("stick takes LX, LY, RX or RY and a value -1..1");
      } else {
        pad.axes[kSticks.at(arg(1))] = static_cast<float>(value);
      }
    } else if (op == "button") {
      if ((arg(1) != "A" && arg(1) != "B") || (arg(2) != "down" && arg(2) != "up")) {
        fail("button takes A or B, then down or up");
      } else {
        pad.buttons[arg(1) == "A" ? GamepadState::kA : GamepadState::kB] = arg(2) == "down";
      }
    }
    return false;
  }
  if (op == "expect-log") {
    // Some line of the event log holds TEXT (the board's worker may still be writing it).
    for (const LogLine& logged : snapshot.log) {
      if (logged.text.find(arg(1)) != std::string::npos) return true;
    }
    if (now_s - started_s_ < 3.0) return false;
    fail("no line of the event log says \"" + arg(1) + "\"");
    return true;
  }
  if (op == "hang") {
    // The panel stops drawing (as when a window is dragged on some systems): nothing reads the
    // pad or says the worker may go on.
    double ms = 0;
    if (!number(arg(1), ms)) fail("hang takes milliseconds");
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(ms));
    return true;
  }
  if (op == "focus") {
    if (arg(1) != "lost" && arg(1) != "back") fail("focus takes lost or back");
    focused_ = arg(1) == "back";
    return frames_ > 1;
  }
  if (op == "screenshot") {
    if (frames_ == 0) {
      screenshot_ = arg(1).empty() ? std::string("screenshot") : arg(1);
      return false;
    }
    return !screenshot_;
  }
  if (op == "quit") {
    finished_ = true;
    return true;
  }
  return true;
}

bool ScriptDriver::take_click(const std::string& key) {
  if (!click_ || *click_ != key) return false;
  click_.reset();
  return true;
}

std::optional<std::vector<double>> ScriptDriver::take_values(const std::string& key) {
  auto it = values_.find(key);
  if (it == values_.end()) return std::nullopt;
  std::vector<double> v = std::move(it->second);
  values_.erase(it);
  return v;
}

std::optional<std::string> ScriptDriver::take_text(const std::string& key) {
  auto it = texts_.find(key);
  if (it == texts_.end()) return std::nullopt;
  std::string text = std::move(it->second);
  texts_.erase(it);
  return text;
}

std::optional<std::string> ScriptDriver::take_key() {
  std::optional<std::string> name = std::move(key_);
  key_.reset();
  return name;
}

std::optional<std::string> ScriptDriver::take_screenshot() {
  std::optional<std::string> name = std::move(screenshot_);
  screenshot_.reset();
  return name;
}

}  // namespace hmc::desk
