// Pictures of signed images (derivatives): a diverging blue–white–red colormap as in the papers' figures.
#pragma once
#include "core/image.h"

namespace penumbra {

// Maps the channel mean v of each pixel to blue (v = -scale) – white (0) – red (v = +scale), clamped. With
// scale <= 0 the 99th percentile of |v| is used. Returns linear RGB (write_image encodes sRGB for PNG).
Image diverging_colormap(const Image& signed_image, float scale = 0.f);
// The scale diverging_colormap() would pick automatically.
float robust_scale(const Image& signed_image);

} // namespace penumbra
