// JSON forms of commands, diagnostics and warnings.
#include "hmc/command_json.h"

namespace hmc {

nlohmann::json command_to_json(const Command& command) {
  const proto::CommandSpec& spec = command_spec(command);
  const CommandValues v = command_values(command);
  nlohmann::json out = {{"name", spec.name}};
  for (uint32_t i = 0; i < v.count; ++i) out[spec.fields[i].name] = v.values[i];
  return out;
}

nlohmann::json diagnostic_to_json(const Diagnostic& d) {
  nlohmann::json out = {{"reason", proto::reason_spec(d.reason).name},
                        {"code", static_cast<int>(d.reason)},
                        {"offset", d.offset},
                        {"message", d.message}};
  out["token"] = d.token == kNoToken ? nlohmann::json(nullptr) : nlohmann::json(d.token);
  out["field"] = d.field;
  out["expected"] = d.expected;
  out["found"] = d.found;
  return out;
}

nlohmann::json warnings_to_json(const std::vector<Warning>& warnings) {
  nlohmann::json out = nlohmann::json::array();
  for (const Warning& w : warnings) out.push_back({{"field", w.field}, {"message", w.message}});
  return out;
}

}  // namespace hmc
