# cmake -DLCM_HEADERS="a.hpp;b.hpp" -P PatchLcmDecoders.cmake
#
# Hardens the C++ decoders that Debian's lcm-gen 1.3.1 generates, in place, right after lcm-gen ran.
# Those decoders trust the length fields of a packet:
#   - a string is read as `if(len > maxlen - pos) return -1; s.assign(p, len - 1); pos += len;`, so a
#     length of 0 throws std::length_error (assign of SIZE_MAX bytes) and a negative one (INT_MIN)
#     passes the check, over-reads and moves `pos` backwards;
#   - the NUL that ends every LCM string on the wire is never looked at, and a NUL inside one is
#     kept (the encoder stops at it, so the message is not what the bytes said);
#   - a variable array is read as `v.resize(this->n)` with no check of n, so a negative count throws
#     std::length_error and a huge one allocates before the data is found missing.
# Debian bookworm ships only 1.3.1 (and we found no upstream release that checks either). This script
# adds the checks: a string length must be at least 1 (it counts the terminating NUL), that NUL must
# be there and be the string's only one, and a count must be 0..bytes left (every element takes at
# least one byte on the wire). It fails the build when the generated code does not look the way it
# expects (a changed lcm-gen), rather than leave a decoder unpatched. The checked decoding layer
# (rig/telemetry/lcm_decode.hpp) catches whatever is still thrown and is the only way vitreo decodes
# outside bytes.
if(NOT LCM_HEADERS)
  message(FATAL_ERROR "PatchLcmDecoders: pass -DLCM_HEADERS=<generated headers>")
endif()
cmake_policy(SET CMP0007 NEW)
set(_marker "// vitreo: length and count checks added by cmake/PatchLcmDecoders.cmake")
foreach(_file IN LISTS LCM_HEADERS)
  file(READ "${_file}" _text)
  string(FIND "${_text}" "${_marker}" _already)
  if(NOT _already EQUAL -1)
    continue()
  endif()
  # Strings: every length check before an assign.
  string(REGEX MATCHALL "\\.assign\\(" _assigns "${_text}")
  string(REGEX REPLACE "if\\((__[A-Za-z0-9_]*len_*) > maxlen - pos\\) return -1;"
                       "if(\\1 < 1 || \\1 > maxlen - pos || ((const char*)buf)[offset + pos + \\1 - 1] != 0 || memchr(((const char*)buf) + offset + pos, 0, \\1 - 1) != NULL) return -1;"
                       _text "${_text}")
  string(REGEX MATCHALL "< 1 \\|\\| __[A-Za-z0-9_]*len_* > maxlen - pos" _string_checks "${_text}")
  # Variable arrays: a count check before every resize.
  string(REGEX MATCHALL "\\.resize\\(" _resizes "${_text}")
  string(REGEX REPLACE "([ \t]*)(this->[A-Za-z0-9_]+(\\[a[0-9]+\\])*)\\.resize\\((this->[A-Za-z0-9_]+)\\);"
                       "\\1if((\\4) < 0 || (\\4) > maxlen - pos) return -1;\n\\1\\2.resize(\\4);" _text "${_text}")
  string(REGEX MATCHALL "\\(this->[A-Za-z0-9_]+\\) < 0 \\|\\| \\(this->[A-Za-z0-9_]+\\) > maxlen - pos" _count_checks "${_text}")
  list(LENGTH _assigns _n_assigns)
  list(LENGTH _string_checks _n_string_checks)
  list(LENGTH _resizes _n_resizes)
  list(LENGTH _count_checks _n_count_checks)
  if(NOT _n_assigns EQUAL _n_string_checks OR NOT _n_resizes EQUAL _n_count_checks)
    message(FATAL_ERROR "PatchLcmDecoders: ${_file}: ${_n_assigns} string decodes but ${_n_string_checks} patched, "
                        "${_n_resizes} array resizes but ${_n_count_checks} patched — lcm-gen's output changed; "
                        "update cmake/PatchLcmDecoders.cmake")
  endif()
  file(WRITE "${_file}" "${_marker}\n${_text}")
endforeach()
