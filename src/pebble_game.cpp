#include "budjam/pebble_game.hpp"

#include <boost/graph/depth_first_search.hpp>
#include <algorithm>
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
  for (std::size_t k = 0; k < joints; ++k) add_joint();
}

std::uint32_t PebbleGame::add_joint() {
  const auto v = static_cast<std::uint32_t>(boost::add_vertex(g_));
  free_.push_back(2);
  stamp_.push_back(0);
  color_.push_back(boost::white_color);
  pred_.push_back(v);
  return v;
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

  struct Recorder : boost::default_dfs_visitor {
    PebbleGame* game;
    void discover_vertex(Vertex v, const Digraph&) const { game->visited_.push_back(static_cast<std::uint32_t>(v)); }
    void tree_edge(Digraph::edge_descriptor e, const Digraph& g) const {
      game->pred_[boost::target(e, g)] = static_cast<std::uint32_t>(boost::source(e, g));
    }
  };
  // Stops expanding once a free pebble is found (BGL's terminator only prunes the vertex it is
  // called on; with out-degree ≤ 2 the remaining work after the hit is a few edges per stack level).
  struct Stop {
    const PebbleGame* game;
    std::uint32_t from, keep1, keep2;
    std::uint32_t* found;
    bool operator()(Vertex v, const Digraph&) const {
      if (*found != none) return true;
      if (v != from && v != keep1 && v != keep2 && game->free_[v] > 0) {
        *found = static_cast<std::uint32_t>(v);
        return true;
      }
      return false;
    }
  };

  Recorder recorder;
  recorder.game = this;
  boost::depth_first_visit(g_, from, recorder, StampedColor{stamp_.data(), color_.data(), now_},
                           Stop{this, from, keep1, keep2, &found});
  work_.visited += visited_.size();

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

bool PebbleGame::play(std::uint32_t a, std::uint32_t b) {
  ++work_.bars_tested;
  if (!gather(a, 2, b, 2)) return false;  // a and b lie in a rigid region: the bar is redundant
  boost::add_edge(a, b, g_);                // one of a's pebbles covers the bar
  --free_[a];
  return true;
}

bool PebbleGame::independent_if_added(std::uint32_t a, std::uint32_t b) {
  if (a == b || a >= joints() || b >= joints())
    throw std::invalid_argument("pebble game: bar (" + std::to_string(a) + ", " + std::to_string(b) +
                                ") needs two distinct existing joints");
  ++work_.bars_tested;
  return gather(a, 2, b, 2);
}

bool PebbleGame::add_bar(std::uint32_t a, std::uint32_t b) {
  if (a == b || a >= joints() || b >= joints())
    throw std::invalid_argument("pebble game: bar (" + std::to_string(a) + ", " + std::to_string(b) +
                                ") needs two distinct existing joints");
  const bool ind = play(a, b);
  bars_.push_back({a, b});
  independent_.push_back(ind ? 1 : 0);
  n_independent_ += ind ? 1 : 0;
  return ind;
}

std::size_t PebbleGame::remove_bars(const std::vector<bool>& remove) {
  if (remove.size() != bars_.size()) throw std::invalid_argument("pebble game: remove mask has wrong size");
  bool lost_independent = false;
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
        lost_independent = true;
      }
      continue;
    }
    bars_[kept] = bars_[k];
    independent_[kept] = independent_[k];
    ++kept;
  }
  bars_.resize(kept);
  independent_.resize(kept);
  if (!lost_independent) return 0;
  // The remaining independent bars are still independent; extend them greedily by the bars that
  // were redundant, which yields a basis of the new bar set.
  std::size_t retested = 0;
  for (std::size_t k = 0; k < bars_.size(); ++k) {
    if (independent_[k]) continue;
    ++retested;
    if (play(bars_[k].a, bars_[k].b)) {
      independent_[k] = 1;
      ++n_independent_;
    }
  }
  return retested;
}

RigidClusters PebbleGame::rigid_clusters() {
  const std::size_t n = joints(), m = bars_.size();
  // Undirected incidence (all bars, independent and redundant) in CSR form.
  std::vector<std::size_t> start(n + 1, 0);
  for (const Bar& e : bars_) {
    ++start[e.a + 1];
    ++start[e.b + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> inc(2 * m);  // (neighbour, bar)
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < m; ++k) {
      inc[fill[bars_[k].a]++] = {bars_[k].b, static_cast<std::uint32_t>(k)};
      inc[fill[bars_[k].b]++] = {bars_[k].a, static_cast<std::uint32_t>(k)};
    }
  }

  RigidClusters out;
  out.of_bar.assign(m, -1);
  std::vector<int> rigid_in(n, -1), floppy_in(n, -1);
  std::deque<std::uint32_t> queue;

  for (std::size_t k = 0; k < m; ++k) {
    if (out.of_bar[k] != -1) continue;
    const auto [u, v] = bars_[k];
    // Three pebbles pinned on the bar stand for its rigid-body motions in the plane.
    // (Two on u and one on v, or one on u and two on v when u's search is blocked by v: the
    // closed set reachable from u and v always holds at least three free pebbles.)
    while (free_[u] < 2 && search(u, v, none, true) != none) {
    }
    while (free_[u] + free_[v] < 3)
      if (search(v, u, none, true) == none) throw std::logic_error("pebble game: three pebbles could not be gathered on a bar");
    const int c = static_cast<int>(out.joints.size());
    std::vector<std::uint32_t> members{u, v};
    rigid_in[u] = rigid_in[v] = c;
    queue.assign({u, v});
    while (!queue.empty()) {
      const std::uint32_t x = queue.front();
      queue.pop_front();
      for (std::size_t s = start[x]; s < start[x + 1]; ++s) {
        const std::uint32_t y = inc[s].first;
        if (rigid_in[y] == c || floppy_in[y] == c) continue;
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
          queue.push_back(z);
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
    std::sort(members.begin(), members.end());
    out.joints.push_back(std::move(members));
  }

  // Canonical order, independent of the insertion history.
  std::vector<int> order(out.joints.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int p, int q) { return out.joints[p] < out.joints[q]; });
  std::vector<int> rank(order.size());
  RigidClusters sorted;
  sorted.joints.reserve(order.size());
  for (std::size_t r = 0; r < order.size(); ++r) {
    rank[order[r]] = static_cast<int>(r);
    sorted.joints.push_back(std::move(out.joints[order[r]]));
  }
  sorted.of_bar.resize(m);
  for (std::size_t k = 0; k < m; ++k) sorted.of_bar[k] = rank[out.of_bar[k]];
  return sorted;
}

}  // namespace budjam
