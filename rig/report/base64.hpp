#pragma once
// Base64 (RFC 4648, standard alphabet, padded): a PNG inside the page as a data: URL.
#include <cstdint>
#include <string>
#include <string_view>

namespace vitreo::report {

std::string base64_encode(std::string_view bytes);

}  // namespace vitreo::report
