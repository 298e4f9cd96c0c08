// `hmc ports [--json]`: lists the serial ports (libhmc's list_ports) as a table for people or
// as a JSON array for programs (docs/ports.md). Exit 0, also when there are none; 3 when the
// ports cannot be listed.
#include "ports_command.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "exit_codes.h"
#include "hmc/port_list.h"

namespace hmc::cli {
namespace {

// A USB id as four lower-case hex digits ("0403"), the way lsusb and udev write them.
std::string usb_id(int id) {
  char text[8];
  std::snprintf(text, sizeof text, "%04x", static_cast<unsigned>(id) & 0xFFFFu);
  return text;
}

nlohmann::ordered_json usb_id_json(int id) {
  if (id < 0) return nullptr;
  return usb_id(id);
}

void print_json(const std::vector<PortInfo>& ports) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const PortInfo& port : ports) {
    list.push_back({{"name", port.name},
                    {"description", port.description},
                    {"kind", port.kind},
                    {"usb_vid", usb_id_json(port.usb_vid)},
                    {"usb_pid", usb_id_json(port.usb_pid)},
                    {"manufacturer", port.manufacturer},
                    {"product", port.product},
                    {"serial", port.serial},
                    {"likely_board", port.likely_board}});
  }
  std::cout << list.dump(2) << "\n";
}

void print_table(const std::vector<PortInfo>& ports) {
  if (ports.empty()) {
    std::cout << "no serial ports found; the simulated board is always available as --port sim://\n";
    return;
  }
  struct Row {
    std::string name, usb, description, mark;
  };
  std::vector<Row> rows{{"PORT", "USB", "DESCRIPTION", ""}};
  for (const PortInfo& port : ports) {
    const std::string usb = port.usb_vid >= 0 ? usb_id(port.usb_vid) + ":" + usb_id(port.usb_pid) : "-";
    rows.push_back({port.name, usb, port.description.empty() ? "-" : port.description, port.likely_board ? "board?" : ""});
  }
  size_t name_width = 0;
  size_t usb_width = 0;
  size_t description_width = 0;
  for (const Row& row : rows) {
    name_width = std::max(name_width, row.name.size());
    usb_width = std::max(usb_width, row.usb.size());
    description_width = std::max(description_width, row.description.size());
  }
  for (const Row& row : rows) {
    std::string line = row.name + std::string(name_width - row.name.size() + 2, ' ') + row.usb +
                       std::string(usb_width - row.usb.size() + 2, ' ') + row.description;
    if (!row.mark.empty()) line += std::string(description_width - row.description.size() + 2, ' ') + row.mark;
    std::cout << line << "\n";
  }
  if (std::any_of(ports.begin(), ports.end(), [](const PortInfo& p) { return p.likely_board; })) {
    std::cout << "\nboard? = an FT232R USB-serial bridge (" << usb_id(kBoardUsbVid) << ":" << usb_id(kBoardUsbPid)
              << "), the kind on the board";
    if (const std::optional<std::string> board = find_board_port(ports)) {
      std::cout << "; use it with: --port " << *board;
    }
    std::cout << "\n";
  }
}

}  // namespace

void add_ports_command(CLI::App& app, int& exit_code) {
  auto json = std::make_shared<bool>(false);
  CLI::App* ports = app.add_subcommand("ports", "List the serial ports this machine has, marking the likely board");
  ports->add_flag("--json", *json, "Print a JSON array of the ports (docs/ports.md) instead of a table");
  ports->callback([json, &exit_code] {
    const Result<std::vector<PortInfo>> found = list_ports();
    if (!found) {
      std::cerr << "hmc ports: error: " << found.error().message << "\n";
      exit_code = kExitIo;
      return;
    }
    if (*json) {
      print_json(*found);
    } else {
      print_table(*found);
    }
    exit_code = kExitOk;
  });
}

}  // namespace hmc::cli
