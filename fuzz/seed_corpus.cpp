// Writes the fuzzers' seed corpus: one file per conformance vector, holding the vector's input
// bytes (a `line` vector gets its LF, so it is judged when fed as a stream).
// Usage: seed_corpus VECTORS_DIR OUT_DIR
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

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: seed_corpus VECTORS_DIR OUT_DIR\n");
    return 2;
  }
  try {
    const fs::path vectors_dir = argv[1];
    const fs::path out_dir = argv[2];
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
      for (const nlohmann::json& vector : doc.at("vectors")) {
        const std::string kind = vector.at("kind").get<std::string>();
        if (kind != "line" && kind != "stream") continue;  // behaviour vectors are scripts
        const std::string id = vector.at("id").get<std::string>();
        std::string bytes = hmc::conformance::input_bytes(vector.at("input").get<std::string>());
        if (kind == "line") bytes += '\n';
        std::ofstream out(out_dir / file_name(id), std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        if (!out) throw std::runtime_error("cannot write " + (out_dir / file_name(id)).string());
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
