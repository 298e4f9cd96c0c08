// Writes the fuzzers' seed corpus: one file per conformance vector, holding the vector's input
// bytes (a `line` vector gets its LF, so it is judged when fed as a stream).
// With --board it writes the board -> host seeds of the replies target instead: one file per
// `board_line` vector (its line and LF), and one per behaviour-script step that expects replies
// or events (those lines, each with its LF; `expect_legacy` too).
// Usage: seed_corpus [--board] VECTORS_DIR OUT_DIR
#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vector_input.h"

namespace {

namespace fs = std::filesystem;

// A vector id as a file name: anything but letters, digits, '-', '_' and '.' becomes '_'.
std::string file_name(const std::string& id) {
  std::string out = id;
  for (char& c : out) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
                       c == '_' || c == '.';
    if (!plain) c = '_';
  }
  return out;
}

void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

// The board -> host seeds of one vector file; returns how many it wrote.
std::size_t write_board_seeds(const nlohmann::json& doc, const fs::path& out_dir) {
  std::size_t written = 0;
  for (const nlohmann::json& vector : doc.at("vectors")) {
    const std::string kind = vector.at("kind").get<std::string>();
    const std::string id = vector.at("id").get<std::string>();
    if (kind == "board_line") {
      write_file(out_dir / file_name(id), hmc::conformance::input_bytes(vector.at("input").get<std::string>()) + '\n');
      ++written;
      continue;
    }
    if (kind != "behaviour" || !vector.contains("script")) continue;
    std::size_t step = 0;
    for (const nlohmann::json& s : vector.at("script")) {
      ++step;
      for (const char* key : {"expect", "expect_legacy"}) {
        if (!s.contains(key)) continue;
        std::string bytes;
        for (const char* list : {"replies", "events"}) {
          if (!s.at(key).contains(list)) continue;
          for (const nlohmann::json& line : s.at(key).at(list)) bytes += line.get<std::string>() + '\n';
        }
        if (bytes.empty()) continue;
        const std::string suffix = std::string(key) == "expect" ? "" : "-legacy";
        write_file(out_dir / file_name(id + "-step" + std::to_string(step) + suffix), bytes);
        ++written;
      }
    }
  }
  return written;
}

}  // namespace

int main(int argc, char** argv) {
  const bool board = argc == 4 && std::string(argv[1]) == "--board";
  if (argc != 3 && !board) {
    std::fprintf(stderr, "usage: seed_corpus [--board] VECTORS_DIR OUT_DIR\n");
    return 2;
  }
  try {
    const fs::path vectors_dir = argv[board ? 2 : 1];
    const fs::path out_dir = argv[board ? 3 : 2];
    fs::create_directories(out_dir);

    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(vectors_dir)) {
      if (entry.path().extension() == ".json") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());

    std::size_t written = 0;
    for (const fs::path& file : files) {
      std::ifstream in(file);
      const nlohmann::json doc = nlohmann::json::parse(in);
      if (board) {
        written += write_board_seeds(doc, out_dir);
        continue;
      }
      for (const nlohmann::json& vector : doc.at("vectors")) {
        const std::string kind = vector.at("kind").get<std::string>();
        if (kind != "line" && kind != "stream") continue;  // behaviour vectors are scripts
        const std::string id = vector.at("id").get<std::string>();
        std::string bytes = hmc::conformance::input_bytes(vector.at("input").get<std::string>());
        if (kind == "line") bytes += '\n';
        write_file(out_dir / file_name(id), bytes);
        ++written;
      }
    }
    std::printf("seed_corpus: %zu inputs from %zu vector files into %s\n", written, files.size(),
                out_dir.string().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "seed_corpus: %s\n", e.what());
    return 1;
  }
  return 0;
}
