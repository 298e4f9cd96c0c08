// list_ports(): the serial ports libserialport finds, with their USB identity, for `hmc ports`
// and for picking the board's port without being told.
#include "hmc/port_list.h"

#include <libserialport.h>

#include <algorithm>
#include <utility>

namespace hmc {
namespace {

std::string text(const char* s) { return s != nullptr ? s : ""; }

std::string kind_of(sp_transport transport) {
  switch (transport) {
    case SP_TRANSPORT_USB: return "usb";
    case SP_TRANSPORT_NATIVE: return "native";
    case SP_TRANSPORT_BLUETOOTH: return "bluetooth";
  }
  return "virtual";
}

PortInfo describe(const sp_port* port) {
  PortInfo info;
  info.name = text(sp_get_port_name(port));
  info.description = text(sp_get_port_description(port));
  const sp_transport transport = sp_get_port_transport(port);
  info.kind = kind_of(transport);
  if (transport == SP_TRANSPORT_USB) {
    int vid = -1;
    int pid = -1;
    if (sp_get_port_usb_vid_pid(port, &vid, &pid) == SP_OK) {
      info.usb_vid = vid;
      info.usb_pid = pid;
    }
    info.manufacturer = text(sp_get_port_usb_manufacturer(port));
    info.product = text(sp_get_port_usb_product(port));
    info.serial = text(sp_get_port_usb_serial(port));
  }
  info.likely_board = info.usb_vid == kBoardUsbVid && info.usb_pid == kBoardUsbPid;
  return info;
}

}  // namespace

Result<std::vector<PortInfo>> list_ports() {
  sp_port** ports = nullptr;
  if (sp_list_ports(&ports) != SP_OK) {
    char* message = sp_last_error_message();
    std::string why = text(message);
    sp_free_error_message(message);
    return Error{"cannot list the serial ports: " + (why.empty() ? std::string("unknown error") : why)};
  }
  std::vector<PortInfo> found;
  for (size_t i = 0; ports != nullptr && ports[i] != nullptr; ++i) found.push_back(describe(ports[i]));
  sp_free_port_list(ports);
  std::sort(found.begin(), found.end(), [](const PortInfo& a, const PortInfo& b) { return a.name < b.name; });
  return found;
}

std::optional<std::string> find_board_port(const std::vector<PortInfo>& ports) {
  std::optional<std::string> board;
  for (const PortInfo& port : ports) {
    if (!port.likely_board) continue;
    if (board) return std::nullopt;  // more than one: the user has to say which
    board = port.name;
  }
  return board;
}

}  // namespace hmc
