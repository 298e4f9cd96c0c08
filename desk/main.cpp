// hmc-desk: the desktop panel for the board. Opens the window (GLFW, OpenGL 3, Dear ImGui),
// loads the machine profile (as the hmc command does: --profile, HMC_PROFILE, the default path),
// starts the board worker and draws the panel once a frame, reading the keyboard and the gamepad;
// with --script it plays a test script against the panel and saves screenshots.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <sys/stat.h>
#include <vector>

#include "board_worker.h"
#include "gamepad.h"
#include "panel.h"
#include "png_writer.h"
#include "script.h"

namespace {

constexpr int kWidth = 1280;
constexpr int kHeight = 800;

void usage(FILE* out) {
  std::fputs(
      "usage: hmc-desk [--profile FILE] [--port PORT] [--baud N] [--script FILE --screenshot-dir DIR]\n"
      "  --profile FILE       the machine profile (docs/config.md); default: HMC_PROFILE, else\n"
      "                       $XDG_CONFIG_HOME/hmc/config.toml when it exists\n"
      "  --port PORT          the board's port (sim://desk, tcp://HOST:PORT, /dev/ttyUSB0);\n"
      "                       default: the profile's; the panel connects to it at once\n"
      "  --baud N             serial speed (default: the profile's, else 115200)\n"
      "  --script FILE        test mode: play FILE against the panel (docs/desk.md)\n"
      "  --screenshot-dir DIR where the script's screenshots go (default .)\n",
      out);
}

// Presses a key the script names, as GLFW's key callback would ("Right", "shift+PageUp", "+",
// "space"): a key code held for one frame, or a typed character. Returns the key code held.
int press_scripted_key(const std::string& name, ImGuiIO& io) {
  const bool shift = name.rfind("shift+", 0) == 0;
  const std::string key = shift ? name.substr(6) : name;
  static const std::pair<const char*, int> kKeys[] = {{"Right", GLFW_KEY_RIGHT}, {"Left", GLFW_KEY_LEFT},
                                                      {"Up", GLFW_KEY_UP},       {"Down", GLFW_KEY_DOWN},
                                                      {"PageUp", GLFW_KEY_PAGE_UP}, {"PageDown", GLFW_KEY_PAGE_DOWN}};
  for (const auto& [text, code] : kKeys) {
    if (key != text) continue;
    io.KeysDown[code] = true;
    io.KeyShift = shift;
    return code;
  }
  io.AddInputCharacter(key == "space" ? ' ' : static_cast<unsigned char>(key.empty() ? 0 : key[0]));
  return -1;
}

// The frame just drawn (the back buffer), top row first, as a PNG.
bool save_screenshot(const std::string& path, int width, int height) {
  std::vector<uint8_t> pixels(static_cast<size_t>(width) * static_cast<size_t>(height) * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
  // OpenGL's rows run bottom-up.
  const size_t row = static_cast<size_t>(width) * 3;
  std::vector<uint8_t> flipped(pixels.size());
  for (size_t y = 0; y < static_cast<size_t>(height); ++y) {
    std::copy_n(pixels.begin() + static_cast<std::ptrdiff_t>((static_cast<size_t>(height) - 1 - y) * row),
                row, flipped.begin() + static_cast<std::ptrdiff_t>(y * row));
  }
  return hmc::desk::write_png(path, static_cast<uint32_t>(width), static_cast<uint32_t>(height), flipped);
}

void style_panel() {
  ImGui::StyleColorsDark();
  ImGuiStyle& s = ImGui::GetStyle();
  s.WindowPadding = ImVec2{10, 10};
  s.FramePadding = ImVec2{8, 5};
  s.ItemSpacing = ImVec2{8, 7};
  s.FrameRounding = 4;
  s.ChildRounding = 6;
  s.GrabRounding = 4;
  s.WindowBorderSize = 0;
  s.Colors[ImGuiCol_WindowBg] = ImVec4{0.10f, 0.11f, 0.13f, 1.0f};
  s.Colors[ImGuiCol_ChildBg] = ImVec4{0.14f, 0.15f, 0.18f, 1.0f};
  s.Colors[ImGuiCol_Border] = ImVec4{0.25f, 0.27f, 0.31f, 1.0f};
  // A readable font when the system has one (fonts-dejavu-core); the built-in one otherwise.
  ImGuiIO& io = ImGui::GetIO();
  const char* font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  struct stat st {};
  if (stat(font, &st) == 0) {
    static const ImWchar ranges[] = {0x0020, 0x00FF, 0x2190, 0x21FF, 0x25A0, 0x25FF, 0};
    io.Fonts->AddFontFromFileTTF(font, 16.0f, nullptr, ranges);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string port, script_path, shot_dir = ".", profile_path;
  std::optional<uint32_t> baud;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "hmc-desk: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--profile") {
      profile_path = value();
    } else if (a == "--port") {
      port = value();
    } else if (a == "--baud") {
      baud = static_cast<uint32_t>(std::strtoul(value().c_str(), nullptr, 10));
    } else if (a == "--script") {
      script_path = value();
    } else if (a == "--screenshot-dir") {
      shot_dir = value();
    } else if (a == "--help" || a == "-h") {
      usage(stdout);
      return 0;
    } else {
      std::fprintf(stderr, "hmc-desk: unknown argument '%s'\n", a.c_str());
      usage(stderr);
      return 2;
    }
  }

  // The profile as the hmc command finds it; one with mistakes is reported and nothing starts.
  std::optional<hmc::Profile> profile;
  if (hmc::Result<hmc::ProfileSource> source = hmc::find_profile(profile_path); source && source->exists) {
    hmc::Result<hmc::Profile, hmc::ProfileError> loaded = hmc::load_profile(source->path);
    if (!loaded) {
      std::fprintf(stderr, "%s", loaded.error().text().c_str());
      std::fprintf(stderr, "hmc-desk: the profile %s (%s) has mistakes: fix them, or name another with --profile\n",
                   source->path.c_str(), source->from.c_str());
      return 1;
    }
    profile = std::move(*loaded);
  } else if (source && source->from != "default") {
    std::fprintf(stderr, "hmc-desk: the profile %s (%s) does not exist\n", source->path.c_str(), source->from.c_str());
    return 1;
  }
  if (port.empty() && profile && profile->port) port = *profile->port;
  if (!baud) baud = profile && profile->baud ? *profile->baud : hmc::kDefaultBaud;

  hmc::desk::ScriptDriver script;
  const bool scripted = !script_path.empty();
  if (scripted) {
    std::string error;
    if (!script.load(script_path, error)) {
      std::fprintf(stderr, "hmc-desk: %s\n", error.c_str());
      return 2;
    }
  }

  if (!glfwInit()) {
    std::fprintf(stderr, "hmc-desk: no display (is DISPLAY set?)\n");
    return 1;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  GLFWwindow* window = glfwCreateWindow(kWidth, kHeight, "hmc-desk", nullptr, nullptr);
  if (!window) {
    std::fprintf(stderr, "hmc-desk: cannot open an OpenGL 3 window\n");
    glfwTerminate();
    return 1;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // the layout is fixed: nothing to remember
  style_panel();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 130");

  int exit_code = 0;
  {
    const hmc::Profile* axes = profile ? &*profile : nullptr;
    hmc::desk::BoardWorker worker(axes);
    hmc::desk::GlfwGamepads pads;
    hmc::desk::Panel panel(worker, scripted ? &script : nullptr, port, *baud, axes,
                           scripted ? script.gamepad() : static_cast<hmc::desk::GamepadSource&>(pads));
    int scripted_key = -1;  // the key code the script holds down this frame
    if (!scripted && !port.empty()) {
      hmc::desk::Request connect(hmc::desk::Request::Kind::kConnect, port);
      connect.baud = *baud;
      worker.post(connect);
    }
    while (!glfwWindowShouldClose(window)) {
      // Redrawn a few times a second even when idle: the board's state changes on its own.
      glfwWaitEventsTimeout(1.0 / 30.0);
      if (scripted) {
        script.advance(glfwGetTime(), worker.snapshot());
        if (script.finished()) break;
      }
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      if (scripted) {
        ImGuiIO& io = ImGui::GetIO();
        if (scripted_key >= 0) {
          io.KeysDown[scripted_key] = false;
          io.KeyShift = false;
          scripted_key = -1;
        }
        if (auto key = script.take_key()) scripted_key = press_scripted_key(*key, io);
      }
      ImGui::NewFrame();
      int fb_w = 0, fb_h = 0;
      glfwGetFramebufferSize(window, &fb_w, &fb_h);
      const ImVec2 size = ImGui::GetIO().DisplaySize;
      // Without the focus the gamepad drives nothing (the script plays the window manager's part).
      const bool focused = scripted ? script.focused() : glfwGetWindowAttrib(window, GLFW_FOCUSED) == GLFW_TRUE;
      panel.draw(size.x, size.y, focused);
      ImGui::Render();
      glViewport(0, 0, fb_w, fb_h);
      glClearColor(0.10f, 0.11f, 0.13f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      if (scripted) {
        if (auto name = script.take_screenshot()) {
          const std::string path = shot_dir + "/" + *name + ".png";
          if (!save_screenshot(path, fb_w, fb_h)) {
            std::fprintf(stderr, "hmc-desk: cannot write %s\n", path.c_str());
            exit_code = 1;
          }
        }
      }
      glfwSwapBuffers(window);
    }
    if (scripted && !script.failures().empty()) exit_code = 1;
  }  // the worker stops its motors (a gamepad's run included) and closes the port here

  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return exit_code;
}
