// What the agreement tests need to prove their own power: renders with a test-only wrapper
// around the named sampler, and a check that a bound sees a 5% bias.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "support/test_support.h"

namespace rll::test {

// Makes the sampler a render uses of the one it names (a test-only wrapper such as BiasedSampler),
// given the render's scene and light tree.
using SamplerWrap =
    std::function<std::unique_ptr<LightSampler>(LightSampler&, const Scene&, const LightTree&)>;
// render_scene, with the sampler `wrap` makes of the requested one (none: the requested one).
Image render_scene_wrapped(const Scene& scene, const RenderRequest& request,
                           const SamplerWrap& wrap);
Image render_scene_wrapped(const Scene& scene, const LightTree& tree, const RenderRequest& request,
                           const SamplerWrap& wrap);

// An agreement bound's power: the smallest bias of `a` proportional to the image (a made brighter
// and darker by a share of itself) that the whole-image bound of 4.5 standard errors on the mean
// difference of a and b rejects both ways, and how many of the nx x ny regions would each reject
// a 5% brighter `a` in them. Printed ("[ power    ]") and
// recorded as a test property under `what`.
std::string bound_power(const Image& a, const Image& b, const std::string& what, int nx = 4,
                        int ny = 4);
// Checked in the test that uses the bound: it must reject `a` made `bias` brighter and darker (a
// sampler or integrator that far off everywhere); each test states the bias it sees, with its
// measured figure, and asks for 0.05 where it sees that.
void expect_bound_sees(const Image& a, const Image& b, const std::string& what, double bias);

}  // namespace rll::test
