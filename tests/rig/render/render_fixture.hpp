#pragma once
// A GL context and a stereo renderer for a test, rendering a FrameScene into a StereoFrame: what the
// renderer's tests share.
#include <gtest/gtest.h>

#include <memory>

#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/renderer.hpp"

namespace vitreo::render::testing {

template <int Width, int Height>
class RendererFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    EglOptions o;
    o.honour_environment = false;  // the default platform order, whatever the shell says
    context_ = std::make_unique<EglContext>(o);
    renderer_ = std::make_unique<StereoRenderer>(RenderSettings{Width, Height, 512, 512});
  }
  StereoFrame render(const FrameScene& s) {
    StereoFrame f;
    renderer_->render(s, f);
    return f;
  }
  std::unique_ptr<EglContext> context_;
  std::unique_ptr<StereoRenderer> renderer_;
};

}  // namespace vitreo::render::testing
