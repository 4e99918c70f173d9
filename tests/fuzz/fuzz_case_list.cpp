// libFuzzer target: the case list a recording's header carries (decode_case_list). Refused text
// must leave the configuration alone; accepted text must re-encode to itself.
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "rig/session/simulation_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  vitreo::rig::ModelConfig m;
  try {
    vitreo::rig::decode_case_list(text, m);
  } catch (const std::runtime_error&) {
    if (!m.cases.empty()) std::abort();
    return 0;
  }
  if (m.cases.empty() || m.first_case < 0 || m.first_case >= static_cast<int>(m.cases.size())) std::abort();
  // Keys may come in any order and repeat in the text; the canonical encoding must decode the same.
  vitreo::rig::ModelConfig again;
  vitreo::rig::decode_case_list(vitreo::rig::encode_case_list(m), again);
  if (again.cases.size() != m.cases.size() || again.first_case != m.first_case ||
      again.load.retina_vertices != m.load.retina_vertices || again.load.texture_size_px != m.load.texture_size_px)
    std::abort();
  for (std::size_t i = 0; i < m.cases.size(); ++i) {
    if (again.cases[i].file_name != m.cases[i].file_name || again.cases[i].text != m.cases[i].text ||
        again.cases[i].library_text != m.cases[i].library_text)
      std::abort();
  }
  return 0;
}
