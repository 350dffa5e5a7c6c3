#pragma once
// Blended feather looks (issue #30 item 2; docs/feather-format.md, "Material blending"): a feather
// interpolated from key feathers looks like the weighted blend of their looks, by the weights of its
// geometry. The pipeline says which key materials a blended material mixes and by how much
// (pipeline::CoatMaterial::blend); this is the renderer side, which turns those parts into one
// FeatherMaterial. Pure CPU code: no GL.
#include <functional>
#include <string>
#include <vector>

#include "pteryla/render/image.hpp"
#include "pteryla/render/renderer.hpp"

namespace pteryla::render {

// `src` resampled bilinearly to width x height (sampled at texel centres, clamped to the edge): a copy
// when the size is already right. Throws pteryla::Error for an empty source or a non-positive size.
Image resampleImage(const Image& src, int width, int height);

// Whether two materials look the same: every field but the name equal, images byte for byte.
bool sameLook(const FeatherMaterial& a, const FeatherMaterial& b);

// Reads the image behind a texture path (blends of file textures); may throw pteryla::Error.
using ImageLoader = std::function<const Image&(const std::string& path)>;

// The look of `parts` blended by `weights` (one per part, > 0, summing to 1), named `name`:
//  - parts that all look the same (sameLook): parts[0] itself, so a blend of one look is that look
//    bit for bit;
//  - colour: base colour x colour texture per texel. Parts sharing one texture (or all without one)
//    keep it and blend their base colours; otherwise the texture is baked: every part's base colour x
//    texture is resampled to the largest texture's size (a part without a texture is its base colour,
//    opaque) and blended with its alpha (the vane outline) as weight, alpha = the weighted sum of the
//    parts' alphas, base colour white. The colour mapping (colorUv) is the heaviest part's;
//  - barb alpha mask: kept when every part has the same one, else the red channels resampled to the
//    largest mask and blended;
//  - Poulin-Fournier barbules (d, h, sigma), barbule angle, specular, cone width, translucency and sheath
//    colour: weighted sums (kept exactly when every part has the same value); useBrdf: the heaviest's.
// Images behind colorTexture / alphaTexture paths come from `load` (only when a texture is baked).
FeatherMaterial blendFeatherMaterials(const std::vector<FeatherMaterial>& parts, const std::vector<double>& weights,
                                      const std::string& name, const ImageLoader& load);

}  // namespace pteryla::render
