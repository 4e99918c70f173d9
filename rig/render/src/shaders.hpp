#pragma once
// GLSL 4.50 sources of the renderer (see shaders.cpp for what each does and why).
#include <string>

namespace vitreo::render::shaders {
extern const char* const kSceneVertex;
extern const char* const kSceneFragmentBody;  // needs "#version 450 core" and the variant defines before it
extern const char* const kShadowVertex;
extern const char* const kShadowFragment;
extern const char* const kCompositeVertex;
extern const char* const kCompositeFragment;
extern const char* const kBurnVertex;
extern const char* const kBurnFragment;
extern const char* const kTextVertex;
extern const char* const kTextFragment;

// One compiled variant of the scene fragment shader (the defines in shaders.cpp).
struct FragmentVariant {
  int material = 0;  // MaterialKind, or 8 for the fluid–gas interface
  bool light = false, shadows = false, light2 = false, gas = false, texture = false, burns = false, flat = false;
};
std::string scene_fragment_source(const FragmentVariant& variant);
}  // namespace vitreo::render::shaders
