// Keeps the tables in docs/protocol.md equal to protocol_facts.h: each table between
// "<!-- generated from protocol_facts.h: NAME -->" and "<!-- end -->" must be what this renders.
// On a mismatch the test prints the table to paste.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>

#include "core/protocol_facts.h"

namespace {

namespace proto = hmc::proto;

std::string commands_table() {
  std::ostringstream out;
  out << "| name | len | values | summary |\n|---|---|---|---|\n";
  for (const auto& c : proto::kCommands) {
    out << "| `" << c.name << "` | " << c.value_count + 1 << " | ";
    for (uint32_t i = 0; i < c.value_count; ++i) out << (i ? ", " : "") << c.fields[i].name;
    out << " | " << c.summary << " |\n";
  }
  return out.str();
}

std::string fields_table() {
  std::ostringstream out;
  out << "| command | field | range | meaning |\n|---|---|---|---|\n";
  for (const auto& c : proto::kCommands) {
    for (uint32_t i = 0; i < c.value_count; ++i) {
      const proto::FieldSpec& f = c.fields[i];
      out << "| " << c.name << " | " << f.name << " | " << f.min << "–" << f.max;
      if (f.flags & proto::kPowerOfTwo) out << ", power of two";
      if (f.advised_min || f.advised_max) out << " (advised " << f.advised_min << "–" << f.advised_max << ")";
      if (f.flags & proto::kUncheckedOnStop) out << "; not checked on stop";
      if (f.flags & proto::kZeroAllowedOnHome) out << "; 0 allowed on home";
      out << " | " << f.meaning << " |\n";
    }
  }
  return out.str();
}

std::string reasons_table() {
  std::ostringstream out;
  out << "| code | name | meaning |\n|---|---|---|\n";
  for (const auto& r : proto::kReasons) {
    if (r.reason == proto::Reason::kOk) continue;
    out << "| " << static_cast<int>(r.reason) << " | `" << r.name << "` | " << r.text << " |\n";
  }
  return out.str();
}

std::string section(const std::string& doc, const std::string& name) {
  const std::string open = "<!-- generated from protocol_facts.h: " + name + " -->\n";
  const auto begin = doc.find(open);
  if (begin == std::string::npos) return "(no section '" + name + "')";
  const auto end = doc.find("<!-- end -->", begin);
  return doc.substr(begin + open.size(), end - begin - open.size());
}

}  // namespace

TEST_CASE("docs/protocol.md tables match protocol_facts.h") {
  std::ifstream in(HMC_PROTOCOL_DOC);
  REQUIRE(in.good());
  std::stringstream doc;
  doc << in.rdbuf();
  CHECK(section(doc.str(), "commands") == commands_table());
  CHECK(section(doc.str(), "fields") == fields_table());
  CHECK(section(doc.str(), "reasons") == reasons_table());
}
