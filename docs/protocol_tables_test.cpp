// Keeps the tables in docs/protocol.md equal to protocol_facts.h: each table between
// "<!-- generated from protocol_facts.h: NAME -->" and "<!-- end -->" must be what this renders.
// On a mismatch the test prints the table to paste, unwrapped, on standard output.
#include <catch2/catch.hpp>

#include <fstream>
#include <iostream>
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
    if (c.value_count == 0) out << "none";
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
      if (f.flags & proto::kSettingValue) out << "; the setting's range (settings table)";
      out << " | " << f.meaning << " |\n";
    }
  }
  return out.str();
}

std::string settings_table() {
  std::ostringstream out;
  out << "| id | name | range | default | meaning |\n|---|---|---|---|---|\n";
  for (uint32_t i = 0; i < proto::kSettingCount; ++i) {
    const proto::SettingSpec& s = proto::kSettings[i];
    out << "| " << i + 1 << " | `" << s.name << "` | " << s.min << "–" << s.max << " | " << s.initial << " | "
        << s.meaning << " |\n";
  }
  return out.str();
}

std::string board_frames_table() {
  std::ostringstream out;
  out << "| name | len | values | kind | summary |\n|---|---|---|---|---|\n";
  for (const auto& f : proto::kBoardFrames) {
    out << "| `" << f.name << "` | " << f.value_count + 1 << " | ";
    for (uint32_t i = 0; i < f.value_count; ++i) out << (i ? ", " : "") << f.fields[i].name;
    if (f.value_count == 0) out << "none";
    out << " | " << (proto::is_event(f) ? "event" : "reply") << " | " << f.summary << " |\n";
  }
  return out.str();
}

std::string board_fields_table() {
  std::ostringstream out;
  out << "| frame | field | range | meaning |\n|---|---|---|---|\n";
  for (const auto& frame : proto::kBoardFrames) {
    for (uint32_t i = 0; i < frame.value_count; ++i) {
      const proto::FieldSpec& f = frame.fields[i];
      out << "| " << frame.name << " | " << f.name << " | " << f.min << "–" << f.max;
      if (f.flags & proto::kSettingValue) out << "; the setting's range (settings table)";
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

std::string features_table() {
  std::ostringstream out;
  out << "| feature | since protocol | what |\n|---|---|---|\n";
  for (const auto& f : proto::kFeatures) out << "| `" << f.name << "` | " << f.since << " | " << f.text << " |\n";
  return out.str();
}

std::string reset_causes_table() {
  std::ostringstream out;
  out << "| cause | name |\n|---|---|\n";
  for (uint32_t i = 0; i < proto::kResetCauseCount; ++i) out << "| " << i << " | `" << proto::kResetCauseNames[i] << "` |\n";
  return out.str();
}

std::string section(const std::string& doc, const std::string& name) {
  const std::string open = "<!-- generated from protocol_facts.h: " + name + " -->\n";
  const auto begin = doc.find(open);
  if (begin == std::string::npos) return "(no section '" + name + "')";
  const auto end = doc.find("<!-- end -->", begin);
  return doc.substr(begin + open.size(), end - begin - open.size());
}

// Checks one generated section; on a mismatch prints what belongs between its markers.
void check_section(const std::string& doc, const std::string& name, const std::string& table) {
  INFO("section '" << name << "' of docs/protocol.md differs from protocol_facts.h; the table to paste is printed");
  const bool same = section(doc, name) == table;
  if (!same) {
    std::cout << "---- paste between <!-- generated from protocol_facts.h: " << name << " --> and <!-- end -->:\n"
              << table << "----\n";
  }
  CHECK(same);
}

}  // namespace

TEST_CASE("docs/protocol.md tables match protocol_facts.h") {
  std::ifstream in(HMC_PROTOCOL_DOC);
  REQUIRE(in.good());
  std::stringstream doc;
  doc << in.rdbuf();
  check_section(doc.str(), "commands", commands_table());
  check_section(doc.str(), "fields", fields_table());
  check_section(doc.str(), "reasons", reasons_table());
  check_section(doc.str(), "settings", settings_table());
  check_section(doc.str(), "board frames", board_frames_table());
  check_section(doc.str(), "board fields", board_fields_table());
  check_section(doc.str(), "features", features_table());
  check_section(doc.str(), "reset causes", reset_causes_table());
}
