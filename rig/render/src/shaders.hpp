#pragma once
// GLSL 4.50 sources of the renderer (see shaders.cpp for what each does and why).
namespace vitreo::render::shaders {
extern const char* const kSceneVertex;
extern const char* const kSceneFragmentBody;  // needs "#version 450 core" and the variant defines before it
extern const char* const kShadowVertex;
extern const char* const kShadowFragment;
extern const char* const kCompositeVertex;
extern const char* const kCompositeFragment;
extern const char* const kBurnVertex;
extern const char* const kBurnFragment;
}  // namespace vitreo::render::shaders
