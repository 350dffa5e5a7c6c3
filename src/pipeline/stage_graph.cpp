#include "stage_graph.hpp"

#include "pteryla/core/error.hpp"

namespace pteryla::pipeline {

StageGraph::Id StageGraph::add(const std::string& name, const std::vector<Id>& inputs, std::function<void()> compute) {
  const Id id = static_cast<Id>(nodes_.size());
  for (Id in : inputs) PTERYLA_CHECK(in >= 0 && in < id, "stage inputs must be added before the stage");
  nodes_.push_back(Node{name, inputs, {}, std::move(compute)});
  for (Id in : inputs) nodes_[in].outputs.push_back(id);
  return id;
}

void StageGraph::invalidate(Id s) {
  // Stages are added in topological order, so one forward sweep reaches everything downstream.
  std::vector<char> mark(nodes_.size(), 0);
  mark[s] = 1;
  for (size_t i = static_cast<size_t>(s); i < nodes_.size(); ++i) {
    if (!mark[i]) continue;
    nodes_[i].dirty = true;
    for (Id o : nodes_[i].outputs) mark[o] = 1;
  }
}

void StageGraph::invalidateAll() {
  for (auto& n : nodes_) n.dirty = true;
}

void StageGraph::pull(Id s) {
  Node& n = nodes_[s];
  if (!n.dirty) return;
  for (Id in : n.inputs) pull(in);
  const auto t0 = std::chrono::steady_clock::now();
  if (n.compute) n.compute();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  n.dirty = false;
  ++n.evaluations;
  n.lastSeconds = secs;
  n.totalSeconds += secs;
}

void StageGraph::resetTimings() {
  for (auto& n : nodes_) {
    n.totalSeconds = 0;
    n.lastSeconds = 0;
  }
}

}  // namespace pteryla::pipeline
