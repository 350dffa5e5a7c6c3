// coat::Packer (packer.hpp): the packer's entry points with what repeated packs share, and the free
// functions of pack.hpp as a Packer used once. The packing itself is pack.cpp's and pack_deformed.cpp's.
#include "pteryla/coat/packer.hpp"

#include <cstring>
#include <utility>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat {

using namespace packing;

Packer::Packer(const SkinMesh& skin, const PackOptions& options) : skin_(&skin), options_(options) {}

void Packer::use(const SkinMesh& skin, const PackOptions& options) {
  skin_ = &skin;
  options_ = options;
}

const PackResult& Packer::keep(PackResult&& r) {
  result_ = std::move(r);
  resultOptions_ = options_;
  hasResult_ = true;
  if (result_.skinSamples) samples_ = result_.skinSamples;
  return result_;
}

// The last result can seed a repack: packed with these options (threads aside) on this skin.
bool Packer::resultFits() const {
  return hasResult_ && sameKnobs(resultOptions_, options_) && packedOnSkin(result_, *skin_, options_);
}

const PackResult& Packer::pack(const CoatFeathers& coat, const PackConstraints& constraints) {
  PTERYLA_CHECK(skin_ != nullptr, "Packer::pack needs a skin (Packer::use)");
  Context ctx(*skin_, coat, options_, constraints);
  ctx.reusable = {samples_, nullptr};
  return keep(packAll(ctx));
}

const PackResult& Packer::repack(const CoatFeathers& coat, const std::vector<uint32_t>& changed,
                                 const PackConstraints& constraints) {
  PTERYLA_CHECK(skin_ != nullptr, "Packer::repack needs a skin (Packer::use)");
  if (!resultFits()) return pack(coat, constraints);
  Context ctx(*skin_, coat, options_, constraints);
  ctx.reusable = {samples_, nullptr};
  return keep(packing::repackFrom(ctx, result_, changed));
}

const PackResult& Packer::repackFrom(const PackResult& previous, const CoatFeathers& coat,
                                     const std::vector<uint32_t>& changed, const PackConstraints& constraints) {
  PTERYLA_CHECK(skin_ != nullptr, "Packer::repackFrom needs a skin (Packer::use)");
  if (!packedOnSkin(previous, *skin_, options_)) return pack(coat, constraints);
  Context ctx(*skin_, coat, options_, constraints);
  ctx.reusable = {samples_, previous.skinSamples};
  return keep(packing::repackFrom(ctx, previous, changed));
}

const PackResult& Packer::packOver(const PackResult& base, const CoatFeathers& coat,
                                   const std::vector<uint32_t>& changed, const PackConstraints& constraints) {
  PTERYLA_CHECK(skin_ != nullptr, "Packer::packOver needs a skin (Packer::use)");
  Context ctx(*skin_, coat, options_, constraints);
  return keep(packOverBase(ctx, base, changed));
}

const PackResult& Packer::packDeformed(const CoatFeathers& coat, const SkinMesh& refSkin,
                                       const std::vector<FeatherFrame>& refFrames, const PackResult& ref,
                                       double tolerance, const PackConstraints& constraints, DeformedPackStats* stats) {
  PTERYLA_CHECK(skin_ != nullptr, "Packer::packDeformed needs a skin (Packer::use)");
  Context ctx(*skin_, coat, options_, constraints);
  ctx.reusable = {samples_, nullptr};
  return keep(packDeformedFrom(ctx, refSkin, refFrames, ref, tolerance, stats));
}

const PackResult& Packer::assign(const PackResult& r) {
  if (&r == &result_) return result_;
  return keep(PackResult(r));
}

PackResult Packer::release() {
  hasResult_ = false;
  return std::move(result_);
}

void Packer::clear() {
  result_ = PackResult{};
  hasResult_ = false;
  samples_.reset();
}

// ------------------------------------------------------------------ the free functions

namespace {
// A Packer used once: `call` packs with it, the result is handed out.
template <class Call>
PackResult once(const SkinMesh& skin, const PackOptions& options, Call&& call) {
  Packer p(skin, options);
  call(p);
  return p.release();
}
}  // namespace

PackResult pack(const SkinMesh& skin, const CoatFeathers& coat, const PackOptions& options,
                const PackConstraints& constraints) {
  return once(skin, options, [&](Packer& p) { p.pack(coat, constraints); });
}

PackResult repack(const SkinMesh& skin, const CoatFeathers& coat, const PackResult& previous,
                  const std::vector<uint32_t>& changed, const PackOptions& options,
                  const PackConstraints& constraints) {
  return once(skin, options, [&](Packer& p) { p.repackFrom(previous, coat, changed, constraints); });
}

PackResult packOver(const SkinMesh& skin, const CoatFeathers& coat, const PackResult& base,
                    const std::vector<uint32_t>& changed, const PackOptions& options,
                    const PackConstraints& constraints) {
  return once(skin, options, [&](Packer& p) { p.packOver(base, coat, changed, constraints); });
}

PackResult packDeformed(const SkinMesh& skin, const CoatFeathers& coat, const SkinMesh& refSkin,
                        const std::vector<FeatherFrame>& refFrames, const PackResult& ref, double tolerance,
                        const PackOptions& options, const PackConstraints& constraints, DeformedPackStats* stats) {
  return once(skin, options,
              [&](Packer& p) { p.packDeformed(coat, refSkin, refFrames, ref, tolerance, constraints, stats); });
}

}  // namespace pteryla::coat
