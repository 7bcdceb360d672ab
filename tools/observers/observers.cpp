#include "observers/observers.hpp"

#include <algorithm>

namespace budjam::tools {

std::vector<ObserverEntry>& observer_registry() {
  static std::vector<ObserverEntry> registry;
  return registry;
}

ObserverRegistration::ObserverRegistration(std::string name, io::OwnedEntries files, ObserverFactory factory) {
  observer_registry().push_back({std::move(name), std::move(files), std::move(factory)});
}

io::OwnedEntries declared_observer_files() {
  io::OwnedEntries out;
  for (const auto& e : observer_registry()) out.insert(out.end(), e.files.begin(), e.files.end());
  return out;
}

std::vector<std::unique_ptr<Observer>> make_observers(const ObserverContext& ctx) {
  std::vector<const ObserverEntry*> entries;
  for (const auto& e : observer_registry()) entries.push_back(&e);
  std::sort(entries.begin(), entries.end(), [](auto* a, auto* b) { return a->name < b->name; });
  for (std::size_t k = 1; k < entries.size(); ++k)
    if (entries[k]->name == entries[k - 1]->name)
      throw InputError("observers: two observers registered as '" + entries[k]->name + "'");
  std::vector<std::unique_ptr<Observer>> out;
  for (const auto* e : entries)
    if (auto obs = e->factory(ctx)) out.push_back(std::move(obs));
  return out;
}

}  // namespace budjam::tools
