// behaviour_session: prints what a behaviour vector sends, or the replies it expects, so a
// session over a real link (hmc-sim on TCP or a pseudo-terminal) can be checked against the
// same vector the simulated board is held to.
//   behaviour_session VECTORS_DIR ID input     the bytes the vector sends, each send + LF
//   behaviour_session VECTORS_DIR ID replies   every expected reply line, in order
// Only vectors whose script is sends and reply expectations make sense on a link; others
// are refused (exit 1), as are unknown ids.
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

using json = nlohmann::json;

namespace {

const json* find_vector(const std::filesystem::path& dir, const std::string& id, json& storage) {
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename().string().rfind("behaviour_", 0) != 0) continue;
    std::ifstream in(entry.path());
    json file = json::parse(in);
    for (json& vector : file.at("vectors")) {
      if (vector.at("id") == id) {
        storage = std::move(vector);
        return &storage;
      }
    }
  }
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 || (std::string(argv[3]) != "input" && std::string(argv[3]) != "replies")) {
    std::fprintf(stderr, "usage: behaviour_session VECTORS_DIR ID input|replies\n");
    return 2;
  }
  try {
    json storage;
    const json* vector = find_vector(argv[1], argv[2], storage);
    if (vector == nullptr) {
      std::fprintf(stderr, "behaviour_session: no behaviour vector '%s'\n", argv[2]);
      return 1;
    }
    const bool input = std::string(argv[3]) == "input";
    for (const json& step : vector->at("script")) {
      for (const auto& [key, value] : step.items()) {
        if (key != "at_ms" && key != "send" && key != "expect") {
          std::fprintf(stderr, "behaviour_session: '%s' uses '%s', which a link cannot play\n", argv[2], key.c_str());
          return 1;
        }
      }
      if (input && step.contains("send")) std::cout << step.at("send").get<std::string>() << '\n';
      if (!input && step.contains("expect") && step.at("expect").contains("replies")) {
        for (const json& reply : step.at("expect").at("replies")) std::cout << reply.get<std::string>() << '\n';
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "behaviour_session: %s\n", e.what());
    return 1;
  }
  return 0;
}
