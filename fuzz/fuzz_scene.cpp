// libFuzzer entry for the scene-file and transfer-function JSON parsers: the input is parsed as a
// scene and as a transfer function; only exa::Error may escape, and what parses must write back
// to JSON that parses to the same text.
#include "exabricks/core/error.h"
#include "exabricks/render/scene.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const exa::SceneDocument doc = exa::readSceneJson(text, "fuzz.json");
    const std::string written = exa::writeSceneJson(doc);
    exa::SceneDocument copy = exa::readSceneJson(written, "written.json");
    if (exa::writeSceneJson(copy) != written) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const exa::TransferFunction tf = exa::parseTransferFunction(text, "fuzz.json");
    const exa::TransferFunction back = exa::parseTransferFunction(exa::transferFunctionJson(tf), "written.json");
    if (exa::transferFunctionJson(back) != exa::transferFunctionJson(tf)) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
