#pragma once
// StageGraph: the dependency-graph core of the evaluation pipeline, in the spirit of a DCC node graph.
// Each stage owns a cached result elsewhere (in Pipeline) and is recomputed only when dirty.
// invalidate(s) dirties s and everything downstream of it, so an edit to packing settings repacks
// without re-relaxing follicles, and a timeline scrub does not reload the mesh.
// The graph records per-stage evaluation counts and the seconds of the last evaluation (for bench).
// Internal to the pipeline: clients address stages through Pipeline by pipeline::Stage (stage.hpp).
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pteryla::pipeline {

class StageGraph {
 public:
  using Id = int;

  // Adds a stage that depends on `inputs` (already added). Returns its id.
  Id add(const std::string& name, const std::vector<Id>& inputs, std::function<void()> compute);

  // Marks s and every stage downstream of it dirty.
  void invalidate(Id s);
  void invalidateAll();
  bool dirty(Id s) const { return nodes_[s].dirty; }

  // Brings s up to date: first its inputs (in dependency order), then s itself if dirty.
  void pull(Id s);

  const std::string& name(Id s) const { return nodes_[s].name; }
  size_t size() const { return nodes_.size(); }
  uint64_t evaluations(Id s) const { return nodes_[s].evaluations; }
  double lastSeconds(Id s) const { return nodes_[s].lastSeconds; }
  // Seconds summed over every evaluation since the last resetTimings().
  double totalSeconds(Id s) const { return nodes_[s].totalSeconds; }
  void resetTimings();

 private:
  struct Node {
    std::string name;
    std::vector<Id> inputs, outputs;
    std::function<void()> compute;
    bool dirty = true;
    uint64_t evaluations = 0;
    double lastSeconds = 0, totalSeconds = 0;
  };
  std::vector<Node> nodes_;
};

}  // namespace pteryla::pipeline
