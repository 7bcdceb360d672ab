#include "observers/observers.hpp"

#include <algorithm>

namespace budjam::tools {

std::vector<ObserverEntry>& observer_registry() {
  static std::vector<ObserverEntry> registry;
  return registry;
}

ObserverRegistration::ObserverRegistration(std::string name, std::string switched_on_by, io::OwnedEntries files,
                                           ObserverFactory factory) {
  observer_registry().push_back({std::move(name), std::move(switched_on_by), std::move(files), std::move(factory)});
}

namespace {

// The registry in name order; InputError if two registrations share a name.
std::vector<const ObserverEntry*> by_name() {
  std::vector<const ObserverEntry*> entries;
  for (const auto& e : observer_registry()) entries.push_back(&e);
  std::sort(entries.begin(), entries.end(), [](auto* a, auto* b) { return a->name < b->name; });
  for (std::size_t k = 1; k < entries.size(); ++k)
    if (entries[k]->name == entries[k - 1]->name)
      throw InputError("observers: two observers registered as '" + entries[k]->name + "'");
  return entries;
}

// "`a`, `b`" (`quote` around each), or `none` for an observer that writes no file.
std::string file_list(const io::OwnedEntries& files, const char* quote, const char* none) {
  std::string text;
  for (const auto& f : files) text += (text.empty() ? "" : ", ") + (quote + f + quote);
  return text.empty() ? none : text;
}

}  // namespace

io::OwnedEntries declared_observer_files() {
  io::OwnedEntries out;
  for (const auto& e : observer_registry()) out.insert(out.end(), e.files.begin(), e.files.end());
  return out;
}

std::vector<std::unique_ptr<Observer>> make_observers(const ObserverContext& ctx) {
  std::vector<std::unique_ptr<Observer>> out;
  for (const auto* e : by_name())
    if (auto obs = e->factory(ctx)) out.push_back(std::move(obs));
  return out;
}

std::string observers_markdown() {
  std::string text = "| observer | switched on by | writes |\n|---|---|---|\n";
  for (const auto* e : by_name())
    text += "| `" + e->name + "` | `" + e->switched_on_by + "` | " + file_list(e->files, "`", "none") + " |\n";
  return text;
}

std::string observers_help() {
  std::string text = "Observers (each built only if its [observe] keys ask for it):";
  for (const auto* e : by_name())
    text += "\n  " + e->name + " (" + e->switched_on_by + "): " + file_list(e->files, "", "no file");
  return text;
}

}  // namespace budjam::tools
