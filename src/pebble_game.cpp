#include "budjam/pebble_game.hpp"

#include <algorithm>
#include <boost/graph/breadth_first_search.hpp>
#include <deque>
#include <numeric>
#include <stdexcept>
#include <string>

namespace budjam {

namespace {

// A colour map that is white for every joint not touched by the current search: a joint's
// colour is valid only if its stamp equals the search's stamp. This keeps one search O(size of
// what it visits) instead of O(joints) for clearing a colour array.
struct StampedColor {
  using key_type = std::size_t;
  using value_type = boost::default_color_type;
  using reference = value_type;
  using category = boost::read_write_property_map_tag;
  std::uint32_t* stamp;
  boost::default_color_type* color;
  std::uint32_t now;
};

inline boost::default_color_type get(const StampedColor& m, std::size_t v) {
  return m.stamp[v] == m.now ? m.color[v] : boost::white_color;
}

inline void put(const StampedColor& m, std::size_t v, boost::default_color_type c) {
  m.stamp[v] = m.now;
  m.color[v] = c;
}

// Undirected incidence of all bars (independent and redundant) in CSR form: the entries of joint
// x are inc[start[x]] … inc[start[x + 1] − 1], each (neighbour, bar), in bar order.
struct Incidence {
  std::vector<std::size_t> start;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> inc;
};

Incidence incidence(std::size_t joints, const std::vector<Bar>& bars) {
  Incidence out;
  out.start.assign(joints + 1, 0);
  for (const Bar& e : bars) {
    ++out.start[e.a + 1];
    ++out.start[e.b + 1];
  }
  std::partial_sum(out.start.begin(), out.start.end(), out.start.begin());
  out.inc.resize(2 * bars.size());
  std::vector<std::size_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::size_t k = 0; k < bars.size(); ++k) {
    out.inc[fill[bars[k].a]++] = {bars[k].b, static_cast<std::uint32_t>(k)};
    out.inc[fill[bars[k].b]++] = {bars[k].a, static_cast<std::uint32_t>(k)};
  }
  return out;
}

}  // namespace

PebbleGame::PebbleGame(std::size_t joints) { reset(joints); }

void PebbleGame::reset(std::size_t joints) {
  g_.clear();
  free_.clear();
  stamp_.clear();
  color_.clear();
  pred_.clear();
  bars_.clear();
  independent_.clear();
  n_independent_ = 0;
  now_ = 0;
  region_.clear();
  region_parent_.clear();
  neighbours_.clear();
  for (std::size_t k = 0; k < joints; ++k) add_joint();
}

std::uint32_t PebbleGame::add_joint() {
  const auto v = static_cast<std::uint32_t>(boost::add_vertex(g_));
  free_.push_back(2);
  stamp_.push_back(0);
  color_.push_back(boost::white_color);
  pred_.push_back(v);
  region_.push_back(-1);
  neighbours_.emplace_back();
  return v;
}

int PebbleGame::region_root(std::uint32_t joint) {
  int r = region_[joint];
  if (r < 0) return -1;
  while (region_parent_[r] != r) {
    region_parent_[r] = region_parent_[region_parent_[r]];  // path halving
    r = region_parent_[r];
  }
  return r;
}

void PebbleGame::record_region(const std::vector<std::uint32_t>& joints) {
  const int id = static_cast<int>(region_parent_.size());
  region_parent_.push_back(id);
  // Regions that share at least two joints with the new one are rigid together with it.
  std::vector<int> roots;
  for (std::uint32_t x : joints)
    if (const int r = region_root(x); r >= 0) roots.push_back(r);
  std::sort(roots.begin(), roots.end());
  for (std::size_t k = 0; k < roots.size();) {
    std::size_t e = k;
    while (e < roots.size() && roots[e] == roots[k]) ++e;
    if (e - k >= 2) region_parent_[roots[k]] = id;
    k = e;
  }
  for (std::uint32_t x : joints) region_[x] = id;
  absorb(joints, id);
}

bool PebbleGame::attached(std::uint32_t joint, int root) {
  // Two bars to two distinct joints of a rigid region pin a joint to it (a triangle on a rigid
  // base, generic positions).
  // Mid-removal, only bars known to lie in the span of the independent ones may certify it.
  std::uint32_t first = none;
  for (const auto& [y, k] : neighbours_[joint]) {
    if (!spanned_ && !independent_[k] && !certified_[k]) continue;
    if (region_root(y) != root) continue;
    if (first == none)
      first = y;
    else if (y != first)
      return true;
  }
  return false;
}

void PebbleGame::absorb(const std::vector<std::uint32_t>& from, int root) {
  std::vector<std::uint32_t> queue(from);
  for (std::size_t h = 0; h < queue.size(); ++h)
    for (const auto& [y, k] : neighbours_[queue[h]])
      if (region_[y] < 0 && attached(y, root)) {
        region_[y] = root;
        queue.push_back(y);
      }
}

void PebbleGame::forget_regions() {
  std::fill(region_.begin(), region_.end(), -1);
  region_parent_.clear();
}

void PebbleGame::next_stamp() {
  if (++now_ == 0) {  // wrapped after 2³² searches: forget all old stamps
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    now_ = 1;
  }
}

std::uint32_t PebbleGame::search(std::uint32_t from, std::uint32_t keep1, std::uint32_t keep2, bool move) {
  next_stamp();
  visited_.clear();
  ++work_.searches;
  std::uint32_t found = none;

  // Breadth first, so that the nearest free pebble is taken: paths stay short and pebbles stay
  // local (depth first wanders through the whole rigid region before turning back).
  struct Recorder : boost::default_bfs_visitor {
    PebbleGame* game;
    std::uint32_t from, keep1, keep2;
    std::uint32_t* found;
    void tree_edge(Digraph::edge_descriptor e, const Digraph& g) const {
      game->pred_[boost::target(e, g)] = static_cast<std::uint32_t>(boost::source(e, g));
    }
    void discover_vertex(Vertex v, const Digraph&) const {
      game->visited_.push_back(static_cast<std::uint32_t>(v));
      if (*found == none && v != from && v != keep1 && v != keep2 && game->free_[v] > 0)
        *found = static_cast<std::uint32_t>(v);
    }
  };
  // BGL's BFS runs while its buffer is not empty: this buffer reports empty once a free pebble
  // has been found, which ends the search cleanly.
  struct StoppingQueue {
    std::vector<std::uint32_t>* items;
    std::size_t head = 0;
    const std::uint32_t* found;
    void push(Vertex v) { items->push_back(static_cast<std::uint32_t>(v)); }
    Vertex top() const { return (*items)[head]; }
    void pop() { ++head; }
    bool empty() const { return *found != none || head == items->size(); }
  };

  Recorder recorder;
  recorder.game = this;
  recorder.from = from;
  recorder.keep1 = keep1;
  recorder.keep2 = keep2;
  recorder.found = &found;
  queue_.clear();
  StoppingQueue queue{&queue_, 0, &found};
  boost::breadth_first_visit(g_, static_cast<Vertex>(from), queue, recorder,
                             StampedColor{stamp_.data(), color_.data(), now_});
  work_.visited += visited_.size();
  if (found == none) {
    ++work_.failed;
    work_.visited_failed += visited_.size();
  }

  if (found != none && move) {
    // Reverse the covered bars along the path from → … → found: the pebble at `found` now covers
    // the last bar, which frees one pebble at each step back to `from`.
    for (std::uint32_t v = found; v != from;) {
      const std::uint32_t u = pred_[v];
      boost::remove_edge(u, v, g_);
      boost::add_edge(v, u, g_);
      v = u;
    }
    --free_[found];
    ++free_[from];
  }
  return found;
}

bool PebbleGame::gather(std::uint32_t a, int want_a, std::uint32_t b, int want_b) {
  while (free_[a] < want_a)
    if (search(a, b, none, true) == none) return false;
  // `a` now holds want_a pebbles; with 2 it has no out-edge, so no path passes through it.
  while (free_[b] < want_b)
    if (search(b, a, none, true) == none) return false;
  return true;
}

bool PebbleGame::test(std::uint32_t a, std::uint32_t b) {
  ++work_.bars_tested;
  if (const int r = region_root(a); r >= 0 && r == region_root(b)) {
    ++work_.quick_rejections;
    return false;
  }
  if (!gather(a, 2, b, 2)) {  // a and b lie in a rigid region: the bar is redundant
    record_region(visited_);
    return false;
  }
  return true;
}

bool PebbleGame::play(std::uint32_t a, std::uint32_t b) {
  if (!test(a, b)) return false;
  boost::add_edge(a, b, g_);  // one of a's four pebbles covers the bar
  --free_[a];
  return true;
}

void PebbleGame::link(std::uint32_t a, std::uint32_t b, std::uint32_t bar) {
  neighbours_[a].push_back({b, bar});
  neighbours_[b].push_back({a, bar});
  // A new bar can pin an unlabelled end to its partner's rigid region.
  for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, a}})
    if (const int r = region_root(x); r >= 0 && region_[y] < 0 && attached(y, r)) {
      region_[y] = r;
      absorb({y}, r);
    }
}

bool PebbleGame::independent_if_added(std::uint32_t a, std::uint32_t b) {
  if (a == b || a >= joints() || b >= joints())
    throw std::invalid_argument("pebble game: bar (" + std::to_string(a) + ", " + std::to_string(b) +
                                ") needs two distinct existing joints");
  return test(a, b);
}

bool PebbleGame::add_bar(std::uint32_t a, std::uint32_t b) {
  if (a == b || a >= joints() || b >= joints())
    throw std::invalid_argument("pebble game: bar (" + std::to_string(a) + ", " + std::to_string(b) +
                                ") needs two distinct existing joints");
  const bool ind = play(a, b);
  link(a, b, static_cast<std::uint32_t>(bars_.size()));
  bars_.push_back({a, b});
  independent_.push_back(ind ? 1 : 0);
  n_independent_ += ind ? 1 : 0;
  return ind;
}

std::size_t PebbleGame::remove_bars(const std::vector<bool>& remove) {
  if (remove.size() != bars_.size()) throw std::invalid_argument("pebble game: remove mask has wrong size");
  std::size_t lost = 0;
  std::vector<std::uint32_t> sources;  // ends of the independent bars that left
  std::size_t kept = 0;
  for (std::size_t k = 0; k < bars_.size(); ++k) {
    if (remove[k]) {
      if (independent_[k]) {
        const auto [a, b] = bars_[k];
        // The bar is covered by a pebble of its tail; give it back.
        if (boost::edge(a, b, g_).second) {
          boost::remove_edge(a, b, g_);
          ++free_[a];
        } else {
          boost::remove_edge(b, a, g_);
          ++free_[b];
        }
        --n_independent_;
        ++lost;
        sources.push_back(a);
        sources.push_back(b);
      }
      continue;
    }
    bars_[kept] = bars_[k];
    independent_[kept] = independent_[k];
    ++kept;
  }
  bars_.resize(kept);
  independent_.resize(kept);
  for (auto& list : neighbours_) list.clear();
  for (std::size_t k = 0; k < bars_.size(); ++k) {
    neighbours_[bars_[k].a].push_back({bars_[k].b, static_cast<std::uint32_t>(k)});
    neighbours_[bars_[k].b].push_back({bars_[k].a, static_cast<std::uint32_t>(k)});
  }
  if (lost == 0) return 0;  // a redundant bar's departure changes neither the rank nor any region
  forget_regions();

  // The surviving independent bars stay independent; extending them by redundant bars gives a
  // basis of what is left. Rank(after) ≤ rank(before), so at most `lost` redundant bars can be
  // promoted, and only one whose circuit contained a removed bar — a rigidity circuit is
  // 2-connected, so it is still connected to the removed bar's ends. Test the redundant bars in
  // breadth-first order from those ends (the likely replacements are close) and stop once `lost`
  // have been promoted.
  const std::size_t n = joints(), m = bars_.size();
  const Incidence incident = incidence(n, bars_);
  const auto& start = incident.start;
  const auto& inc = incident.inc;
  std::vector<char> seen(n, 0);
  certified_.assign(m, 0);  // re-tested: in the span again
  std::deque<std::uint32_t> frontier;
  for (std::uint32_t x : sources)
    if (!seen[x]) {
      seen[x] = 1;
      frontier.push_back(x);
    }
  std::size_t retested = 0, promoted = 0;
  // Until it has been re-tested, a redundant bar may not be in the span of the independent ones:
  // it cannot certify that a joint is attached to a region (attached()).
  spanned_ = false;
  while (!frontier.empty() && promoted < lost) {
    const std::uint32_t x = frontier.front();
    frontier.pop_front();
    for (std::size_t s = start[x]; s < start[x + 1] && promoted < lost; ++s) {
      const auto [y, k] = inc[s];
      if (!seen[y]) {
        seen[y] = 1;
        frontier.push_back(y);
      }
      if (independent_[k] || certified_[k]) continue;
      ++retested;
      if (play(bars_[k].a, bars_[k].b)) {
        independent_[k] = 1;
        ++n_independent_;
        ++promoted;
      }
      certified_[k] = 1;
    }
  }
  spanned_ = true;
  return retested;
}

RigidClusters PebbleGame::rigid_clusters() {
  const std::size_t n = joints(), m = bars_.size();
  const Incidence incident = incidence(n, bars_);
  const auto& start = incident.start;  // (not a structured binding: lambdas below capture it)
  const auto& inc = incident.inc;
  const auto degree = [&](std::uint32_t x) { return start[x + 1] - start[x]; };

  // Bars inside the largest known rigid region first: the big cluster is then found early and
  // its joints are excluded cheaply from every later cluster (two clusters share ≤ 1 joint).
  std::vector<std::size_t> region_size(region_parent_.size(), 0);
  for (std::uint32_t x = 0; x < n; ++x)
    if (const int r = region_root(x); r >= 0) ++region_size[r];
  std::vector<std::size_t> weight(m, 0);
  for (std::size_t k = 0; k < m; ++k)
    if (const int r = region_root(bars_[k].a); r >= 0 && r == region_root(bars_[k].b)) weight[k] = region_size[r];
  std::vector<std::size_t> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return weight[p] > weight[q]; });

  RigidClusters out;
  out.of_bar.assign(m, -1);
  std::vector<int> rigid_in(n, -1), floppy_in(n, -1);
  std::vector<std::vector<int>> clusters_of(n);  // clusters found so far, per joint
  std::vector<char> blocked;                     // per cluster: shares a joint with the current one
  std::vector<int> blocked_list;
  std::deque<std::uint32_t> queue;

  for (std::size_t k : order) {
    if (out.of_bar[k] != -1) continue;
    const auto [u, v] = bars_[k];
    const int c = static_cast<int>(out.joints.size());
    std::vector<std::uint32_t> members{u, v};
    rigid_in[u] = rigid_in[v] = c;
    blocked.push_back(0);
    const auto join = [&](std::uint32_t x) {
      // A joint that shares an earlier cluster with a member is not in this one: the two
      // clusters would share two joints and be one.
      for (int q : clusters_of[x])
        if (!blocked[q]) {
          blocked[q] = 1;
          blocked_list.push_back(q);
        }
    };
    join(u);
    join(v);

    // A joint on a single bar hinges on it: the bar is a cluster by itself (no pebbles needed).
    if (degree(u) > 1 && degree(v) > 1) {
      const int shared = region_root(u) >= 0 && region_root(u) == region_root(v) ? region_root(u) : -1;
      bool gathered = false;
      queue.assign({u, v});
      while (!queue.empty()) {
        const std::uint32_t x = queue.front();
        queue.pop_front();
        for (std::size_t s = start[x]; s < start[x + 1]; ++s) {
          const std::uint32_t y = inc[s].first;
          if (rigid_in[y] == c || floppy_in[y] == c) continue;
          bool in_earlier = false;
          for (int q : clusters_of[y]) in_earlier = in_earlier || blocked[q];
          if (in_earlier || degree(y) == 1) {
            floppy_in[y] = c;
            continue;
          }
          if (shared >= 0 && region_root(y) == shared) {  // u, v, y in one known rigid region
            rigid_in[y] = c;
            members.push_back(y);
            join(y);
            queue.push_back(y);
            continue;
          }
          if (!gathered) {
            // Three pebbles pinned on the bar stand for its rigid-body motions in the plane (two
            // on u and one on v, or the reverse when u's search is blocked by v: the closed set
            // reachable from u and v always holds at least three free pebbles).
            while (free_[u] < 2 && search(u, v, none, true) != none) {}
            while (free_[u] + free_[v] < 3)
              if (search(v, u, none, true) == none)
                throw std::logic_error("pebble game: three pebbles could not be gathered on a bar");
            gathered = true;
          }
          if (free_[y] > 0 || search(y, u, v, false) != none) {
            floppy_in[y] = c;  // y can move with the bar held: not in this cluster
            continue;
          }
          // No free pebble is reachable from y, nor from anything y reaches: all of them are
          // rigid with respect to the bar.
          for (std::uint32_t z : visited_) {
            if (rigid_in[z] == c) continue;
            rigid_in[z] = c;
            members.push_back(z);
            join(z);
            queue.push_back(z);
          }
        }
      }
    }
    for (std::uint32_t x : members)
      for (std::size_t s = start[x]; s < start[x + 1]; ++s)
        if (rigid_in[inc[s].first] == c) {
          int& label = out.of_bar[inc[s].second];
          if (label != -1 && label != c) throw std::logic_error("pebble game: a bar lies in two rigid clusters");
          label = c;
        }
    for (int q : blocked_list) blocked[q] = 0;
    blocked_list.clear();
    for (std::uint32_t x : members) clusters_of[x].push_back(c);
    std::sort(members.begin(), members.end());
    out.joints.push_back(std::move(members));
  }

  // The clusters are the exact rigid regions now: record them (largest last, so that a pivot
  // joint carries the label of its largest cluster) for later insertions.
  forget_regions();
  std::vector<int> by_size(out.joints.size());
  std::iota(by_size.begin(), by_size.end(), 0);
  std::stable_sort(by_size.begin(), by_size.end(),
                   [&](int p, int q) { return out.joints[p].size() < out.joints[q].size(); });
  for (int c : by_size)
    if (out.joints[c].size() >= 3) record_region(out.joints[c]);

  // Canonical order, independent of the insertion history.
  std::vector<int> canon(out.joints.size());
  std::iota(canon.begin(), canon.end(), 0);
  std::sort(canon.begin(), canon.end(), [&](int p, int q) { return out.joints[p] < out.joints[q]; });
  std::vector<int> rank(canon.size());
  RigidClusters sorted;
  sorted.joints.reserve(canon.size());
  for (std::size_t r = 0; r < canon.size(); ++r) {
    rank[canon[r]] = static_cast<int>(r);
    sorted.joints.push_back(std::move(out.joints[canon[r]]));
  }
  sorted.of_bar.resize(m);
  for (std::size_t k = 0; k < m; ++k) sorted.of_bar[k] = rank[out.of_bar[k]];
  return sorted;
}

}  // namespace budjam
