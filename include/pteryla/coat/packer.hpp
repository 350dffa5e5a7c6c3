#pragma once
// coat::Packer: the height-field packer (pack.hpp) as an object that keeps what repeated packs on one skin
// share, so a caller holding a Packer across frames reuses what it may and the rules for when a cached
// piece is stale live here, not in each caller:
//  - the skin samples (the points and patches feathers pack against, 9.1.2): rebuilt only when the skin's
//    positions, faces or face normals, or the sample spacing the coat resolves, differ from those they
//    were built for; a result handed in as a seed (repackFrom, packOver) lends its samples when they fit;
//  - the last result, which repack() starts from: a full pack instead when there is none, or when it was
//    packed with other options or on another skin.
// Every entry point gives the bits of the corresponding free function of pack.hpp (which are thin
// wrappers over a Packer used once), at any thread count.
#include <memory>
#include <vector>

#include "pteryla/coat/pack.hpp"

namespace pteryla::coat {

class Packer {
 public:
  Packer() = default;  // bound to no skin: call use() before packing
  explicit Packer(const SkinMesh& skin, const PackOptions& options = {});

  // Packs on `skin` with `options` from the next call on. The skin is referenced, not copied: it must
  // outlive the calls and may change in place between them (the packer compares it with what its
  // samples and its last result were made from).
  void use(const SkinMesh& skin, const PackOptions& options);
  const SkinMesh* skin() const { return skin_; }
  const PackOptions& options() const { return options_; }

  // A full pack of `coat` (pack()); it becomes result().
  const PackResult& pack(const CoatFeathers& coat, const PackConstraints& constraints = {});
  // An incremental repack (repack()) from result(), with `changed` the feathers whose input differs from
  // the one result() was packed from; a full pack when there is no result or it is stale (packed with
  // other options, threads aside, or on another skin).
  const PackResult& repack(const CoatFeathers& coat, const std::vector<uint32_t>& changed,
                           const PackConstraints& constraints = {});
  // The same from `previous`, a pack of the same coat's earlier state on this skin with these options
  // (another packer's result, say); a full pack when it was packed on another skin. An empty `changed`
  // still checks every feather (nothing is recomputed); assign() takes a result as it is.
  const PackResult& repackFrom(const PackResult& previous, const CoatFeathers& coat,
                               const std::vector<uint32_t>& changed, const PackConstraints& constraints = {});
  // The changed feathers packed over `base` (packOver(): the moult's pack), with base's clearances and
  // skin samples. Error when base does not fit the coat or was packed on another skin.
  const PackResult& packOver(const PackResult& base, const CoatFeathers& coat, const std::vector<uint32_t>& changed,
                             const PackConstraints& constraints = {});
  // The coat on this (deformed) skin from the reference pack `ref` of the coat with frames `refFrames` on
  // `refSkin` (packDeformed()).
  const PackResult& packDeformed(const CoatFeathers& coat, const SkinMesh& refSkin,
                                 const std::vector<FeatherFrame>& refFrames, const PackResult& ref, double tolerance,
                                 const PackConstraints& constraints = {}, DeformedPackStats* stats = nullptr);
  // Takes `r` (a copy) as this packer's result: for a caller that knows its inputs are those `r` was
  // packed from, on this skin with these options.
  const PackResult& assign(const PackResult& r);

  bool hasResult() const { return hasResult_; }
  const PackResult& result() const { return result_; }  // empty before the first pack
  PackResult release();  // moves the result out (hasResult() is then false); the samples stay cached
  void clear();          // forgets the result and the cached samples

 private:
  const PackResult& keep(PackResult&& r);
  bool resultFits() const;

  const SkinMesh* skin_ = nullptr;
  PackOptions options_;
  PackResult result_;
  PackOptions resultOptions_;  // the options result_ was packed with
  bool hasResult_ = false;
  std::shared_ptr<const detail::PackSkinSamples> samples_;  // the last pack's (null without skin)
};

}  // namespace pteryla::coat
