// Registry of feather generators selected by a feather file's "generator" key. "streit" (Streit 2003,
// 5.2.2) is built in; other generators add hooks for reading, writing, generating and blending.
#include "pteryla/feather/generator.hpp"

#include <map>
#include <mutex>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/helical.hpp"

namespace pteryla::feather {

namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, FeatherGenerator> generators;
};

void registerBuiltinFeatherGenerators(Registry& reg);

Registry& registry() {
  static Registry* reg = [] {
    auto* r = new Registry;
    registerBuiltinFeatherGenerators(*r);
    return r;
  }();
  return *reg;
}

void addGenerator(Registry& reg, const std::string& name, FeatherGenerator gen) {
  if (name == "streit" || name.empty()) throw Error("feather generator name '" + name + "' is reserved");
  PTERYLA_CHECK(gen.read && gen.write, "a feather generator needs read and write hooks");
  reg.generators[name] = std::move(gen);
}

// Generators that ship with pteryla register here (static libraries drop self-registering objects).
// Example: addGenerator(reg, "helical", helicalFeatherGenerator());
void registerBuiltinFeatherGenerators(Registry& reg) { addGenerator(reg, "helical", helicalFeatherGenerator()); }

}  // namespace

void registerFeatherGenerator(const std::string& name, FeatherGenerator gen) {
  Registry& reg = registry();
  std::lock_guard<std::mutex> lock(reg.mutex);
  addGenerator(reg, name, std::move(gen));
}

const FeatherGenerator* findFeatherGenerator(const std::string& name) {
  Registry& reg = registry();
  std::lock_guard<std::mutex> lock(reg.mutex);
  const auto it = reg.generators.find(name);
  // std::map nodes are stable: the pointer stays valid unless the entry is replaced.
  return it == reg.generators.end() ? nullptr : &it->second;
}

FeatherParams streitForm(const FeatherParams& p) {
  FeatherParams r = p;
  r.generator = "streit";
  r.generatorParams = nlohmann::json();
  if (p.afterfeather) r.afterfeather = std::make_shared<const FeatherParams>(streitForm(*p.afterfeather));
  return r;
}

std::vector<std::string> featherGeneratorNames() {
  Registry& reg = registry();
  std::lock_guard<std::mutex> lock(reg.mutex);
  std::vector<std::string> names{"streit"};
  for (const auto& kv : reg.generators) names.push_back(kv.first);
  return names;
}

}  // namespace pteryla::feather
