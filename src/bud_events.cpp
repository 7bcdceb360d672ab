#include "budjam/bud_events.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>

namespace budjam {

namespace {

enum : int { kActive = 0, kCompleted = 1, kDivided = 2, kClosed = 3 };

// Cell index of each id; ids are unique.
std::vector<std::pair<std::int64_t, std::size_t>> index_by_id(const Packing& p) {
  std::vector<std::pair<std::int64_t, std::size_t>> v(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) v[i] = {p.id[i], i};
  std::sort(v.begin(), v.end());
  return v;
}

std::size_t find_cell(const std::vector<std::pair<std::int64_t, std::size_t>>& index, std::int64_t id) {
  auto it = std::lower_bound(index.begin(), index.end(), std::make_pair(id, std::size_t{0}));
  if (it == index.end() || it->first != id) throw std::logic_error("BudTracker: tagged cell id not in packing");
  return it->second;
}

}  // namespace

const char* to_string(BudEventKind kind) {
  switch (kind) {
    case BudEventKind::tagged: return "tagged";
    case BudEventKind::first_contact: return "first_contact";
    case BudEventKind::completed: return "completed";
    case BudEventKind::divided: return "divided";
    case BudEventKind::censored_end: return "censored_end";
    case BudEventKind::censored_unjam: return "censored_unjam";
  }
  return "?";
}

std::vector<BudEvent> BudTracker::tag(int episode, long step, double phi, const Packing& p, const ContactNetwork& net) {
  tags_.clear();
  episode_ = episode;
  std::vector<BudEvent> events;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!net.unconstrained_bud(i)) continue;
    tags_.push_back(Tag{p.id[i], p.b[i] * p.b[i]});
    events.push_back(BudEvent{BudEventKind::tagged, episode, p.id[i], step, phi, 0.0});
  }
  std::sort(tags_.begin(), tags_.end(), [](const Tag& a, const Tag& b) { return a.id < b.id; });
  return events;
}

std::vector<BudEvent> BudTracker::update(long step, double phi, const Packing& p, const std::vector<Contact>& contacts,
                                         const ContactNetwork& net, const std::vector<Division>& divisions) {
  std::vector<BudEvent> events;
  if (active() == 0) return events;
  std::vector<char> touching(2 * p.size(), 0);  // lobes with any contact (also with rattlers)
  for (const Contact& c : contacts) touching[c.i] = touching[c.j] = 1;
  const auto index = index_by_id(p);
  for (Tag& t : tags_) {
    if (t.state != kActive) continue;
    auto div = std::find_if(divisions.begin(), divisions.end(), [&](const Division& d) { return d.mother_id == t.id; });
    if (div != divisions.end()) {
      t.state = kDivided;
      events.push_back(BudEvent{BudEventKind::divided, episode_, t.id, step, phi, div->b * div->b - t.b2_J});
      continue;
    }
    const std::size_t i = find_cell(index, t.id);
    const double a = p.b[i] * p.b[i] - t.b2_J;
    if (!t.touched && touching[bud_lobe(i)]) {
      t.touched = true;
      events.push_back(BudEvent{BudEventKind::first_contact, episode_, t.id, step, phi, a});
    }
    if (!net.unconstrained_bud(i)) {
      t.state = kCompleted;
      events.push_back(BudEvent{BudEventKind::completed, episode_, t.id, step, phi, a});
    }
  }
  return events;
}

std::vector<BudEvent> BudTracker::close(BudEventKind kind, long step, double phi, const Packing& p) {
  std::vector<BudEvent> events;
  if (active() == 0) return events;
  const auto index = index_by_id(p);
  for (Tag& t : tags_) {
    if (t.state != kActive) continue;
    const std::size_t i = find_cell(index, t.id);
    t.state = kClosed;
    events.push_back(BudEvent{kind, episode_, t.id, step, phi, p.b[i] * p.b[i] - t.b2_J});
  }
  return events;
}

std::size_t BudTracker::active() const {
  return static_cast<std::size_t>(
      std::count_if(tags_.begin(), tags_.end(), [](const Tag& t) { return t.state == kActive; }));
}
std::size_t BudTracker::completed() const {
  return static_cast<std::size_t>(
      std::count_if(tags_.begin(), tags_.end(), [](const Tag& t) { return t.state == kCompleted; }));
}
std::size_t BudTracker::divided() const {
  return static_cast<std::size_t>(
      std::count_if(tags_.begin(), tags_.end(), [](const Tag& t) { return t.state == kDivided; }));
}
std::size_t BudTracker::touched() const {
  return static_cast<std::size_t>(std::count_if(tags_.begin(), tags_.end(), [](const Tag& t) { return t.touched; }));
}

std::vector<std::string> BudTracker::events_of(std::int64_t id) const {
  const auto t =
      std::lower_bound(tags_.begin(), tags_.end(), id, [](const Tag& x, std::int64_t i) { return x.id < i; });
  if (t == tags_.end() || t->id != id) return {};
  std::vector<std::string> e{to_string(BudEventKind::tagged)};
  if (t->touched) e.emplace_back(to_string(BudEventKind::first_contact));
  if (t->state == 1) e.emplace_back(to_string(BudEventKind::completed));
  if (t->state == 2) e.emplace_back(to_string(BudEventKind::divided));
  if (t->state == 3) e.emplace_back("censored");
  return e;
}

std::vector<std::int64_t> BudTracker::tagged_ids() const {
  std::vector<std::int64_t> ids;
  for (const Tag& t : tags_) ids.push_back(t.id);
  return ids;
}

void BudTracker::save(std::ostream& os) const {
  char buf[64];
  os << "buds " << episode_ << ' ' << tags_.size() << '\n';
  for (const Tag& t : tags_) {
    std::snprintf(buf, sizeof buf, "%.17g", t.b2_J);
    os << t.id << ' ' << buf << ' ' << (t.touched ? 1 : 0) << ' ' << t.state << '\n';
  }
}

void BudTracker::load(std::istream& is) {
  std::string word;
  std::size_t n = 0;
  if (!(is >> word >> episode_ >> n) || word != "buds") throw std::runtime_error("BudTracker: bad checkpoint");
  tags_.assign(n, Tag{});
  for (Tag& t : tags_) {
    std::string b2;
    int touched = 0;
    if (!(is >> t.id >> b2 >> touched >> t.state)) throw std::runtime_error("BudTracker: bad checkpoint");
    t.b2_J = std::strtod(b2.c_str(), nullptr);
    t.touched = touched != 0;
  }
}

}  // namespace budjam
