#include "lab/run/lab_command_writer.h"

#include "core/core_errors.h"

namespace vlab::lab {

void ClaimTable::Add(const CommandWriter& writer) {
  for (const Claim& claim : writer.Claims()) Add(claim);
}

void ClaimTable::Add(const Claim& claim) {
  const auto [it, added] = holders_.emplace(claim.device, claim);
  if (added) return;
  const Claim& first = it->second;
  throw InputError(claim.where + ": " + claim.who + ": device '" + claim.device + "' is driven by " + first.who +
                   (first.where.empty() ? "" : " (" + first.where + ")") + " already: one owner at a time");
}

const Claim* ClaimTable::Holder(const std::string& device) const {
  const auto it = holders_.find(device);
  return it == holders_.end() ? nullptr : &it->second;
}

}  // namespace vlab::lab
