// The function a Highway dispatch table (HWY_EXPORT) holds for the instruction set chosen now,
// as HWY_DYNAMIC_DISPATCH picks it, for callers that call it many times: looked up once, each
// call is then one indirect call. Include after <hwy/highway.h>, in the file that exports the
// table (the lookup uses that file's set of compiled targets).
#pragma once

#include <hwy/highway.h>

namespace exa {

template <typename Function> Function chosenBatchFunction(const Function* table) {
  hwy::ChosenTarget& chosen = hwy::GetChosenTarget();
  if (!chosen.IsInitialized()) chosen.Update(hwy::SupportedTargets());
  return table[chosen.GetIndex()];
}

} // namespace exa
