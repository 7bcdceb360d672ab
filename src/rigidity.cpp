#include "budjam/rigidity.hpp"

#include "budjam/scene.hpp"  // InputError

#include <algorithm>
#include <boost/graph/breadth_first_search.hpp>
#include <boost/graph/filtered_graph.hpp>
#include <boost/property_map/property_map.hpp>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace budjam {

namespace {

std::uint64_t key_of(const Bar& bar) { return (std::uint64_t{bar.a} << 32) | bar.b; }

// Wraps a lobe centre into the primary box, (0 ≤ y < L, then 0 ≤ x < L in the sheared frame).
void wrap(const Box& box, double& x, double& y) {
  const double ny = std::floor(y / box.L);
  y -= ny * box.L;
  x -= box.shear * box.L * ny;
  x -= std::floor(x / box.L) * box.L;
}

ImageShift image_shift(const Box& box, const Lobes& lobes, std::uint32_t a, std::uint32_t b) {
  double dx = lobes.x[b] - lobes.x[a], dy = lobes.y[b] - lobes.y[a];
  box.minimum_image(dx, dy);  // the bar vector: the contact's line of centres, or the cell's axis
  double xa = lobes.x[a], ya = lobes.y[a], xb = lobes.x[b], yb = lobes.y[b];
  wrap(box, xa, ya);
  wrap(box, xb, yb);
  const double rx = xa + dx - xb, ry = ya + dy - yb;
  ImageShift s;
  s.y = static_cast<int>(std::lround(ry / box.L));
  s.x = static_cast<int>(std::lround((rx - box.shear * box.L * s.y) / box.L));
  return s;
}

// Z-order (Morton) index of a point of the box on a 2¹⁶ × 2¹⁶ grid.
std::uint32_t morton(const Box& box, double x, double y) {
  wrap(box, x, y);
  const auto cell = [&](double v) { return static_cast<std::uint32_t>(std::clamp(v / box.L * 65536.0, 0.0, 65535.0)); };
  const std::uint32_t ix = cell(x), iy = cell(y);
  std::uint32_t key = 0;
  for (int bit = 0; bit < 16; ++bit) key |= (((ix >> bit) & 1u) << (2 * bit)) | (((iy >> bit) & 1u) << (2 * bit + 1));
  return key;
}

}  // namespace

std::vector<std::size_t> play_order(const Framework& fw, const Lobes& lobes, const Box& box) {
  std::vector<std::uint32_t> key(fw.bars.size());
  for (std::size_t k = 0; k < fw.bars.size(); ++k) {
    const std::uint32_t mother = fw.bars[k].a & ~1u;
    key[k] = morton(box, lobes.x[mother], lobes.y[mother]);
  }
  std::vector<std::size_t> order(fw.bars.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return key[p] < key[q]; });
  return order;
}

Framework build_framework(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                          const ContactNetwork& net, RigidityNetwork which) {
  const std::size_t n = p.size();
  if (lobes.size() != 2 * n) throw std::invalid_argument("rigidity: lobes do not match the packing");
  if (which == RigidityNetwork::load_bearing && net.rattler.size() != n)
    throw std::invalid_argument("rigidity: contact network does not match the packing");
  Framework fw;
  fw.joints = 2 * n;
  fw.cell_included.assign(n, true);
  if (which == RigidityNetwork::load_bearing)
    for (std::size_t i = 0; i < n; ++i) fw.cell_included[i] = !net.rattler[i];
  fw.cells = static_cast<std::size_t>(std::count(fw.cell_included.begin(), fw.cell_included.end(), true));
  fw.bars.reserve(fw.cells + contacts.size());
  for (std::size_t i = 0; i < n; ++i)
    if (fw.cell_included[i])
      fw.bars.push_back({static_cast<std::uint32_t>(mother_lobe(i)), static_cast<std::uint32_t>(bud_lobe(i))});
  for (const Contact& c : contacts) {
    if (cell_of(c.i) == cell_of(c.j)) throw std::invalid_argument("rigidity: a contact joins two lobes of one cell");
    if (!fw.cell_included[cell_of(c.i)] || !fw.cell_included[cell_of(c.j)]) continue;
    fw.bars.push_back({std::min(c.i, c.j), std::max(c.i, c.j)});
  }
  std::sort(fw.bars.begin(), fw.bars.end(), [](const Bar& u, const Bar& v) { return key_of(u) < key_of(v); });
  fw.shift.reserve(fw.bars.size());
  for (const Bar& bar : fw.bars) fw.shift.push_back(image_shift(p.box, lobes, bar.a, bar.b));
  return fw;
}

std::vector<Winding> cluster_windings(std::size_t joints, const std::vector<Bar>& bars,
                                      const std::vector<ImageShift>& shift, const RigidClusters& clusters) {
  if (shift.size() != bars.size() || clusters.of_bar.size() != bars.size())
    throw std::invalid_argument("rigidity: bars, shifts and clusters do not match");
  using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                                      boost::property<boost::edge_index_t, std::uint32_t>>;
  Graph g(joints);
  for (std::size_t k = 0; k < bars.size(); ++k) boost::add_edge(bars[k].a, bars[k].b, static_cast<std::uint32_t>(k), g);
  using IndexMap = boost::property_map<Graph, boost::edge_index_t>::type;
  const IndexMap bar_index = boost::get(boost::edge_index, g);

  struct InCluster {  // keeps the bars of one cluster
    const std::vector<int>* of_bar = nullptr;
    IndexMap index;
    int cluster = -1;
    bool operator()(Graph::edge_descriptor e) const { return (*of_bar)[boost::get(index, e)] == cluster; }
  };
  using Sub = boost::filtered_graph<Graph, InCluster>;
  InCluster keep{&clusters.of_bar, bar_index, -1};

  std::vector<boost::default_color_type> color(joints, boost::white_color);
  std::vector<ImageShift> offset(joints);
  std::vector<std::uint32_t> touched;

  struct Tracker : boost::default_bfs_visitor {
    const std::vector<Bar>* bars;
    const std::vector<ImageShift>* shift;
    IndexMap index;
    std::vector<ImageShift>* offset;
    std::vector<std::uint32_t>* touched;
    Winding* w;
    // Offset that the edge, walked from its source, assigns to its target.
    ImageShift across(Sub::edge_descriptor e, const Sub& s) const {
      const std::uint32_t k = boost::get(index, e);
      const ImageShift d = (*shift)[k];
      const ImageShift o = (*offset)[boost::source(e, s)];
      return boost::source(e, s) == (*bars)[k].a ? ImageShift{o.x + d.x, o.y + d.y} : ImageShift{o.x - d.x, o.y - d.y};
    }
    void discover_vertex(Sub::vertex_descriptor v, const Sub&) const {
      touched->push_back(static_cast<std::uint32_t>(v));
    }
    void tree_edge(Sub::edge_descriptor e, const Sub& s) const { (*offset)[boost::target(e, s)] = across(e, s); }
    void non_tree_edge(Sub::edge_descriptor e, const Sub& s) const {
      const ImageShift there = across(e, s), here = (*offset)[boost::target(e, s)];
      if (there.x != here.x) w->x = true;
      if (there.y != here.y) w->y = true;
    }
  };

  std::vector<Winding> out(clusters.size());
  boost::queue<Sub::vertex_descriptor> queue;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (clusters.joints[c].empty()) continue;
    // filtered_graph copies its predicate: one view per cluster.
    keep.cluster = static_cast<int>(c);
    const Sub view(g, keep);
    Tracker vis;
    vis.bars = &bars;
    vis.shift = &shift;
    vis.index = bar_index;
    vis.offset = &offset;
    vis.touched = &touched;
    vis.w = &out[c];
    const auto root = clusters.joints[c].front();
    offset[root] = ImageShift{};
    touched.clear();
    boost::breadth_first_visit(view, root, queue, vis,
                               boost::make_iterator_property_map(color.begin(), boost::get(boost::vertex_index, view)));
    for (std::uint32_t v : touched) color[v] = boost::white_color;
    if (touched.size() != clusters.joints[c].size())
      throw std::logic_error("rigidity: a rigid cluster is not connected through its own bars");
  }
  return out;
}

RigidityState summarise_rigidity(PebbleGame& game, const std::vector<ImageShift>& shift,
                                 const std::vector<bool>& cell_included, RigidityNetwork which) {
  RigidityState s;
  s.network = which;
  s.N = cell_included.size();
  s.cells = static_cast<std::size_t>(std::count(cell_included.begin(), cell_included.end(), true));
  s.joints = 2 * s.cells;
  s.bars = game.bars();
  s.independent_bars = game.independent_bars();
  s.redundant_bars = game.redundant_bars();
  // Joints of excluded cells carry no bar and keep their 2 pebbles; they are not counted.
  s.free_pebbles = 2L * static_cast<long>(s.joints) - static_cast<long>(s.independent_bars);
  s.floppy_plane = s.joints ? s.free_pebbles - 3 : 0;
  s.floppy_periodic = s.joints ? s.free_pebbles - 2 : 0;

  const RigidClusters rc = game.rigid_clusters();
  std::vector<Bar> bars(game.bars());
  for (std::size_t k = 0; k < bars.size(); ++k) bars[k] = game.bar(k);
  const std::vector<Winding> wind = cluster_windings(game.joints(), bars, shift, rc);

  s.clusters.resize(rc.size());
  s.cell_cluster.assign(s.N, -1);
  for (std::size_t c = 0; c < rc.size(); ++c) {
    s.clusters[c].joints = rc.joints[c].size();
    s.clusters[c].winding = wind[c];
    if (rc.joints[c].size() >= 3) ++s.nontrivial_clusters;
    s.spans_x = s.spans_x || wind[c].x;
    s.spans_y = s.spans_y || wind[c].y;
  }
  for (std::size_t k = 0; k < bars.size(); ++k) {
    ClusterSummary& cl = s.clusters[rc.of_bar[k]];
    ++cl.bars;
    if (is_cell_bar(bars[k])) {
      ++cl.cells;
      s.cell_cluster[cell_of(bars[k].a)] = rc.of_bar[k];
    } else {
      ++s.contact_bars;
    }
  }
  for (std::size_t c = 0; c < s.clusters.size(); ++c) {
    if (s.largest < 0) {
      s.largest = static_cast<int>(c);
      continue;
    }
    const ClusterSummary &a = s.clusters[c], &b = s.clusters[s.largest];
    if (a.cells > b.cells || (a.cells == b.cells && a.joints > b.joints)) s.largest = static_cast<int>(c);
  }
  return s;
}

RigidityState analyse_rigidity(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                               const ContactNetwork& net, RigidityNetwork which) {
  const Framework fw = build_framework(p, lobes, contacts, net, which);
  PebbleGame game(fw.joints);
  std::vector<ImageShift> shift;
  shift.reserve(fw.bars.size());
  for (std::size_t k : play_order(fw, lobes, p.box)) {
    game.add_bar(fw.bars[k].a, fw.bars[k].b);
    shift.push_back(fw.shift[k]);
  }
  return summarise_rigidity(game, shift, fw.cell_included, which);
}

RigidityNetwork parse_rigidity_network(const std::string& text, const std::string& key) {
  if (text == "load-bearing") return RigidityNetwork::load_bearing;
  if (text == "raw") return RigidityNetwork::raw;
  throw InputError(key + ": must be load-bearing or raw (got " + text + ")");
}

const char* to_string(RigidityEventKind kind) {
  switch (kind) {
    case RigidityEventKind::floppy_modes: return "floppy_modes";
    case RigidityEventKind::spanning: return "spanning";
    case RigidityEventKind::first_spanning: return "first_spanning";
    case RigidityEventKind::bud_rigid: return "bud_rigid";
    case RigidityEventKind::bud_released: return "bud_released";
    case RigidityEventKind::joined_largest: return "joined_largest";
    case RigidityEventKind::left_largest: return "left_largest";
  }
  return "unknown";
}

RigidityTracker::RigidityTracker(RigidityNetwork which, RemovalPolicy policy) : which_(which), policy_(policy) {}

void RigidityTracker::rebuild(const Framework& fw, const std::vector<std::uint64_t>& keys, const Lobes& lobes,
                              const Box& box) {
  game_.reset(fw.joints);
  keys_.clear();
  for (std::size_t k : play_order(fw, lobes, box)) {
    game_.add_bar(fw.bars[k].a, fw.bars[k].b);
    keys_.push_back(keys[k]);
  }
  last_.rebuilt = true;
}

const std::vector<RigidityEvent>& RigidityTracker::update(const Packing& p, const Lobes& lobes,
                                                          const std::vector<Contact>& contacts,
                                                          const ContactNetwork& net) {
  const Framework fw = build_framework(p, lobes, contacts, net, which_);
  std::vector<std::uint64_t> keys(fw.bars.size());
  for (std::size_t k = 0; k < fw.bars.size(); ++k) keys[k] = key_of(fw.bars[k]);  // sorted
  const auto in_new = [&](std::uint64_t key) { return std::binary_search(keys.begin(), keys.end(), key); };

  last_ = RigidityUpdate{};
  if (!game_current_ || game_.joints() > fw.joints) {
    last_.bars_added = fw.bars.size();
    rebuild(fw, keys, lobes, p.box);
  } else {
    std::vector<bool> remove(keys_.size(), false);
    for (std::size_t k = 0; k < keys_.size(); ++k) {
      if (in_new(keys_[k])) continue;
      remove[k] = true;
      ++last_.bars_removed;
      if (game_.independent(k)) ++last_.independent_removed;
    }
    std::vector<std::uint64_t> old_sorted(keys_);
    std::sort(old_sorted.begin(), old_sorted.end());
    for (std::uint64_t key : keys)
      if (!std::binary_search(old_sorted.begin(), old_sorted.end(), key)) ++last_.bars_added;

    if (last_.bars_removed > 0 && policy_ == RemovalPolicy::rebuild) {
      rebuild(fw, keys, lobes, p.box);
    } else {
      while (game_.joints() < fw.joints) game_.add_joint();  // newborn cells
      if (last_.bars_removed > 0) {
        last_.retested = game_.remove_bars(remove);
        std::size_t kept = 0;
        for (std::size_t k = 0; k < keys_.size(); ++k)
          if (!remove[k]) keys_[kept++] = keys_[k];
        keys_.resize(kept);
      }
      for (std::size_t k = 0; k < keys.size(); ++k) {
        if (std::binary_search(old_sorted.begin(), old_sorted.end(), keys[k])) continue;
        game_.add_bar(fw.bars[k].a, fw.bars[k].b);
        keys_.push_back(keys[k]);
      }
    }
  }

  // Image shifts depend on where the joints sit in the box now: take them from the new framework.
  std::vector<ImageShift> shift(keys_.size());
  for (std::size_t k = 0; k < keys_.size(); ++k)
    shift[k] = fw.shift[static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), keys_[k]) - keys.begin())];

  game_current_ = true;
  state_ = summarise_rigidity(game_, shift, fw.cell_included, which_);
  diff_events(p);
  return events_;
}

void RigidityTracker::restore(const RigidityMemory& memory) {
  if (!std::is_sorted(memory.cells.begin(), memory.cells.end()))
    throw std::invalid_argument("rigidity tracker: remembered cells are not sorted by id");
  memory_ = memory;
  game_current_ = false;
  keys_.clear();
}

void RigidityTracker::diff_events(const Packing& p) {
  events_.clear();
  const bool first = !memory_.has_state;
  const long code = long{state_.spans_x} + 2L * long{state_.spans_y};
  if (first || memory_.floppy_plane != state_.floppy_plane)
    events_.push_back({RigidityEventKind::floppy_modes, -1, first ? -1L : memory_.floppy_plane, state_.floppy_plane});
  if (!first && memory_.span_code != code)
    events_.push_back({RigidityEventKind::spanning, -1, memory_.span_code, code});
  if (!memory_.spanned && code != 0) {
    memory_.spanned = true;
    events_.push_back({RigidityEventKind::first_spanning, -1, 0, code});
  }

  std::vector<std::pair<std::int64_t, std::uint8_t>> cells(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::uint8_t f = static_cast<std::uint8_t>((state_.in_largest(i) ? 1 : 0) | (state_.bud_rigid(i) ? 2 : 0));
    cells[i] = {p.id[i], f};
    if (first) continue;
    const auto& old_cells = memory_.cells;
    const auto it = std::lower_bound(old_cells.begin(), old_cells.end(), std::make_pair(p.id[i], std::uint8_t{0}));
    const std::uint8_t old = (it != old_cells.end() && it->first == p.id[i]) ? it->second : 0;  // newborn: 0
    if ((old & 2) != (f & 2))
      events_.push_back({(f & 2) ? RigidityEventKind::bud_rigid : RigidityEventKind::bud_released, p.id[i],
                         (old & 2) ? 1L : 0L, (f & 2) ? 1L : 0L});
    if ((old & 1) != (f & 1))
      events_.push_back({(f & 1) ? RigidityEventKind::joined_largest : RigidityEventKind::left_largest, p.id[i],
                         (old & 1) ? 1L : 0L, (f & 1) ? 1L : 0L});
  }
  std::sort(cells.begin(), cells.end());
  memory_.cells = std::move(cells);
  memory_.has_state = true;
  memory_.floppy_plane = state_.floppy_plane;
  memory_.span_code = code;
}

}  // namespace budjam
