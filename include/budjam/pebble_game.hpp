#pragma once
// The (2,3) pebble game for generic bar-joint frameworks in the plane (Jacobs & Hendrickson,
// J. Comput. Phys. 137, 346 (1997); Jacobs & Thorpe, PRL 75, 4051 (1995)).
//
// Every joint carries two pebbles (its two degrees of freedom). A bar is independent when four
// pebbles can be gathered on its two ends; one of them is then spent to cover the bar, which is
// recorded as a directed edge (tail = the joint whose pebble covers it) in a Boost.Graph digraph.
// Pebbles are moved by a breadth-first search (BGL) along covered bars and reversing the path.
//
// The game is purely combinatorial (generic positions): it knows nothing of a periodic box.
// Counting conventions (floppy modes, trivial motions) belong to the caller (budjam/rigidity.hpp).
#include <boost/graph/adjacency_list.hpp>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace budjam {

struct Bar {
  std::uint32_t a, b;  // joints, a != b
};

// Decomposition of the bars into rigid clusters (maximal rigid subgraphs). Every bar, independent
// or redundant, belongs to exactly one cluster; a joint can belong to several (a pivot).
// Canonical order: clusters sorted by their (sorted) joint lists, so the result does not depend
// on the order in which bars were inserted.
struct RigidClusters {
  std::vector<int> of_bar;                         // cluster index of every bar
  std::vector<std::vector<std::uint32_t>> joints;  // sorted joints of each cluster
  std::size_t size() const { return joints.size(); }
};

// Cumulative work counters, to measure what an update costs.
struct PebbleWork {
  std::size_t searches = 0;          // pebble searches started
  std::size_t visited = 0;           // joints discovered by those searches
  std::size_t failed = 0;            // searches that found no free pebble
  std::size_t visited_failed = 0;    // joints discovered by the failed ones
  std::size_t bars_tested = 0;       // independence tests (insertions and re-tests)
  std::size_t quick_rejections = 0;  // redundant bars recognised from known rigid regions, no search
};

// Invariant: free(v) + out_degree(v) = 2 at every joint, and the covered (independent) bars,
// oriented tail → head, are exactly the edges of the digraph; they form a (2,3)-sparse graph and
// every other bar is in their span (redundant).
class PebbleGame {
 public:
  explicit PebbleGame(std::size_t joints = 0);

  // Back to `joints` bare joints and no bars (the work counters keep counting). Cheaper than
  // assigning a new game, which would copy the Boost graph.
  void reset(std::size_t joints);

  // Appends a joint with its two free pebbles; returns its index.
  std::uint32_t add_joint();

  // Inserts a bar and plays it: returns true if it is independent. The pebble state of all
  // other bars is kept, so insertion costs a few local searches, never a replay.
  bool add_bar(std::uint32_t a, std::uint32_t b);

  // Would bar (a, b) be independent? Moves pebbles but inserts nothing.
  bool independent_if_added(std::uint32_t a, std::uint32_t b);

  // Removes the bars flagged in `remove` (size = bars()); the survivors keep their order.
  // A redundant bar leaves without any work (the independent set is still a basis). An
  // independent bar gives its pebble back to its tail; then redundant bars are re-tested, nearest
  // to the removed bars first, until as many have become independent as independent bars left
  // (the rank cannot exceed its old value) or none can. Returns the number re-tested.
  std::size_t remove_bars(const std::vector<bool>& remove);

  std::size_t joints() const { return free_.size(); }
  std::size_t bars() const { return bars_.size(); }
  const Bar& bar(std::size_t k) const { return bars_[k]; }
  bool independent(std::size_t k) const { return independent_[k] != 0; }
  std::size_t independent_bars() const { return n_independent_; }
  std::size_t redundant_bars() const { return bars_.size() - n_independent_; }
  int free_pebbles(std::uint32_t joint) const { return free_[joint]; }
  // Σ free pebbles = 2·joints − independent bars.
  long free_pebbles() const { return 2L * static_cast<long>(joints()) - static_cast<long>(n_independent_); }

  // Standard decomposition (Jacobs & Hendrickson): for each bar not yet assigned, gather three
  // pebbles on it, pin them, and test the joints around it — a joint that cannot obtain a free
  // pebble is rigid with respect to the bar. Moves pebbles, keeps all counts.
  RigidClusters rigid_clusters();

  const PebbleWork& work() const { return work_; }

 private:
  using Digraph = boost::adjacency_list<boost::vecS, boost::vecS, boost::directedS>;
  using Vertex = Digraph::vertex_descriptor;

  // Breadth-first search from `from` along covered bars for a joint other than `from`, `keep1`,
  // `keep2` holding a free pebble. If found and `move`, the pebble is brought to `from` by
  // reversing the path. Returns the joint found or `none`. The joints discovered by the search
  // are left in `visited_`.
  static constexpr std::uint32_t none = 0xffffffffu;
  std::uint32_t search(std::uint32_t from, std::uint32_t keep1, std::uint32_t keep2, bool move);
  bool gather(std::uint32_t a, int want_a, std::uint32_t b, int want_b);
  bool test(std::uint32_t a, std::uint32_t b);  // could 4 pebbles be gathered on a, b?
  bool play(std::uint32_t a, std::uint32_t b);  // test + cover; true if independent
  void next_stamp();

  // Known rigid regions, so that a bar inside one is rejected without a search. A failed gather
  // leaves in visited_ a closed set holding 3 free pebbles: it spans 2|R| − 3 independent bars, a
  // rigid region, and it stays rigid as bars are added. Regions sharing ≥ 2 joints are merged
  // (union–find); a joint keeps the label of the last region recorded on it, so a lookup may miss
  // (then the search decides) but never errs. Removing an independent bar forgets them all.
  // A joint with bars to two distinct joints of a region joins it (generic triangle), which
  // propagates; this labels rigidly attached joints before any search fails on them.
  int region_root(std::uint32_t joint);
  void record_region(const std::vector<std::uint32_t>& joints);
  void forget_regions();
  bool attached(std::uint32_t joint, int root);
  void absorb(const std::vector<std::uint32_t>& from, int root);
  void link(std::uint32_t a, std::uint32_t b, std::uint32_t bar);  // adjacency + absorption for a new bar

  Digraph g_;
  std::vector<std::uint8_t> free_;
  std::vector<Bar> bars_;
  std::vector<std::uint8_t> independent_;
  std::size_t n_independent_ = 0;
  // Per-search scratch, reset by a stamp instead of an O(joints) clear.
  std::vector<std::uint32_t> stamp_;
  std::vector<boost::default_color_type> color_;
  std::vector<std::uint32_t> pred_;
  std::vector<std::uint32_t> visited_;
  std::vector<std::uint32_t> queue_;
  std::uint32_t now_ = 0;
  std::vector<int> region_;         // per joint: a region id, −1 if none
  std::vector<int> region_parent_;  // union–find over region ids
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> neighbours_;  // per joint: (joint, bar)
  bool spanned_ = true;          // every bar lies in the span of the independent ones (false mid-removal)
  std::vector<char> certified_;  // mid-removal: redundant bars already re-tested
  PebbleWork work_;
};

}  // namespace budjam
