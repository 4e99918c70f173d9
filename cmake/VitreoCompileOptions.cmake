# Compiler options every vitreo target gets through the `vitreo_options` interface library.
# Floating point is kept strict (no contraction into FMA, no fast-math) so the core gives the same
# bits on every machine and every -march level: replay and hardware-in-the-loop tests rely on it.

add_library(vitreo_options INTERFACE)
target_compile_options(vitreo_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow
  $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor> $<$<COMPILE_LANGUAGE:CXX>:-Woverloaded-virtual>
  -Wimplicit-fallthrough -Wformat=2 -Wundef
  -ffp-contract=off -fno-fast-math)

if(VITREO_ARCH)
  target_compile_options(vitreo_options INTERFACE -march=${VITREO_ARCH})
endif()

if(VITREO_WERROR)
  target_compile_options(vitreo_options INTERFACE -Werror)
endif()

if(VITREO_SANITIZE)
  target_compile_options(vitreo_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  target_link_options(vitreo_options INTERFACE -fsanitize=address,undefined)
endif()

if(VITREO_TSAN)
  target_compile_options(vitreo_options INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
  target_link_options(vitreo_options INTERFACE -fsanitize=thread)
endif()

# Unity batches (the sanitizer presets build that way, for time) #include the sources, so
# GCC takes a class defined in a .cpp for one in a header and warns that its members have types from
# an anonymous namespace (-Wsubobject-linkage); inside one translation unit that is harmless.
if(CMAKE_UNITY_BUILD)
  target_compile_options(vitreo_options INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-Wno-subobject-linkage>)
endif()
