#pragma once
// Rigidity of a packing's contact network (docs/model.md, "Contact network"), by the (2,3)
// pebble game, and a tracker that follows it along growth and reports what changed.
//
// Framework: every lobe centre is a joint (lobe 2i = mother of cell i, 2i+1 = its bud); each cell
// of the analysed network contributes its mother–bud bar, each contact between two of its cells
// one bar. A cell is then a rigid body with 2·2 − 1 = 3 degrees of freedom, and a bud with no
// contact hangs on a single bar: one floppy mode (its rotation about the mother).
//
// Counting conventions (see docs/rigidity.md). The pebble game treats the graph as a generic
// framework in the plane: F = Σ free pebbles = 2·joints − independent bars includes the 3 rigid
// motions of the plane (2 translations + 1 rotation).
//   floppy_plane    = F − 3  (trivial motions: 2 translations + rotation)
//   floppy_periodic = F − 2  (trivial motions: the 2 translations of the periodic box only)
// The exact count of a periodic framework lies between: a rigid cluster that winds around the
// box with a self-stress cannot rotate, so for a packing with a spanning self-stressed backbone
// (every packing above jamming) floppy_plane is the periodic count, and for a network in which
// no cycle winds (no spanning) floppy_periodic is. Both are reported.
#include <cstdint>
#include <string>
#include <vector>
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/packing.hpp"
#include "budjam/pebble_game.hpp"

namespace budjam {

// Load-bearing: non-rattler cells and the contacts among them (rattlers removed by the iterative
// rule of ContactNetwork). Raw: every cell and every contact.
enum class RigidityNetwork { load_bearing, raw };
// "load-bearing" | "raw"; throws InputError naming `key` otherwise.
RigidityNetwork parse_rigidity_network(const std::string& text, const std::string& key = "--network");

// Which periodic image of joint b a bar reaches from joint a, in box lengths: with a, b wrapped
// into the box, the bar vector is w_b + (x L + γ L y, y L) − w_a (γ = Lees–Edwards shear).
struct ImageShift {
  int x = 0, y = 0;
  bool operator==(const ImageShift&) const = default;
};

// The bar-joint framework of a packing.
struct Framework {
  std::size_t joints = 0;           // 2N: every lobe has a joint; excluded cells' joints carry no bar
  std::vector<bool> cell_included;  // per cell: part of the analysed network
  std::size_t cells = 0;            // included cells
  std::vector<Bar> bars;            // a < b, sorted by (a, b); (2i, 2i+1) is the bar of cell i
  std::vector<ImageShift> shift;    // per bar
};

inline bool is_cell_bar(const Bar& bar) { return bar.a % 2 == 0 && bar.b == bar.a + 1; }

// Contacts are taken as found (each lobe pair at most once); `net` decides the rattlers.
Framework build_framework(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                          const ContactNetwork& net, RigidityNetwork which);

// The order in which analyse_rigidity (and a tracker rebuild) plays the bars: cell by cell along
// a Z-order curve through the box (a cell's own bar, then its contacts with higher lobes).
// Spatially coherent insertion keeps the known rigid regions compact, so joints get attached to
// them before a search fails on them; on jammed packings it halves the search work of lobe order.
std::vector<std::size_t> play_order(const Framework& fw, const Lobes& lobes, const Box& box);

// Rigidity percolation. Breadth-first search over the bars of each cluster (Boost.Graph),
// carrying the image offset of every joint; a joint reached with two different offsets closes a
// cycle that winds around the box: in x if the offsets differ in x, in y if they differ in y.
struct Winding {
  bool x = false, y = false;
};
std::vector<Winding> cluster_windings(std::size_t joints, const std::vector<Bar>& bars,
                                      const std::vector<ImageShift>& shift, const RigidClusters& clusters);

struct ClusterSummary {
  std::size_t joints = 0;
  std::size_t bars = 0;
  std::size_t cells = 0;  // cells whose mother–bud bar lies in the cluster
  Winding winding;
};

struct RigidityState {
  RigidityNetwork network = RigidityNetwork::load_bearing;
  std::size_t N = 0;       // cells in the packing
  std::size_t cells = 0;   // cells in the analysed network (N_nr when load-bearing)
  std::size_t joints = 0;  // 2·cells
  std::size_t bars = 0;    // cells + contact bars
  std::size_t contact_bars = 0;
  std::size_t independent_bars = 0;
  std::size_t redundant_bars = 0;         // states of self-stress of the generic framework
  long free_pebbles = 0;                  // F = 2·joints − independent_bars
  long floppy_plane = 0;                  // F − 3 (0 for an empty network)
  long floppy_periodic = 0;               // F − 2 (0 for an empty network)
  std::vector<ClusterSummary> clusters;   // canonical order (RigidClusters)
  std::size_t nontrivial_clusters = 0;    // clusters with ≥ 3 joints
  int largest = -1;                       // most cells, then most joints, then lowest index
  bool spans_x = false, spans_y = false;  // some rigid cluster winds the box in x / in y
  std::vector<int> cell_cluster;          // per cell: cluster of its mother–bud bar, −1 if excluded

  std::size_t largest_cells() const { return largest < 0 ? 0 : clusters[largest].cells; }
  std::size_t largest_joints() const { return largest < 0 ? 0 : clusters[largest].joints; }
  bool in_largest(std::size_t cell) const { return largest >= 0 && cell_cluster[cell] == largest; }
  // The bud is rigidly held by more than its own mother: the cell's bar lies in a rigid cluster
  // with ≥ 3 joints. False for a contact-free bud (a joint on one bar is never in such a cluster),
  // and false when the cell as a whole hinges on a single joint.
  bool bud_rigid(std::size_t cell) const { return cell_cluster[cell] >= 0 && clusters[cell_cluster[cell]].joints >= 3; }
};

// Summary of a played game. `shift` is aligned with the game's bars; the cell bars are recognised
// by their joints (is_cell_bar).
RigidityState summarise_rigidity(PebbleGame& game, const std::vector<ImageShift>& shift,
                                 const std::vector<bool>& cell_included, RigidityNetwork which);

// From scratch: framework, one full pebble game, decomposition, percolation.
RigidityState analyse_rigidity(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                               const ContactNetwork& net, RigidityNetwork which = RigidityNetwork::load_bearing);

// ---- following rigidity along growth -----------------------------------------------------

enum class RigidityEventKind {
  floppy_modes,    // floppy_plane changed (before = −1 on the first state)
  spanning,        // spanning code changed; code = spans_x + 2·spans_y
  first_spanning,  // first state with a spanning rigid cluster (after = code)
  bud_rigid,       // bud_rigid(cell) became true
  bud_released,    // bud_rigid(cell) became false
  joined_largest,  // the cell's bar entered the largest rigid cluster
  left_largest,    // ... or left it
};
const char* to_string(RigidityEventKind kind);

struct RigidityEvent {
  RigidityEventKind kind;
  std::int64_t cell = -1;  // lineage id (Packing::id), −1 for global events
  long before = 0, after = 0;
};

// What the last update cost.
struct RigidityUpdate {
  bool rebuilt = false;  // full replay of the game
  std::size_t bars_added = 0;
  std::size_t bars_removed = 0;
  std::size_t independent_removed = 0;
  std::size_t retested = 0;  // redundant bars re-tested after an independent bar left
};

// What a tracker remembers of the previous state: all it needs to diff the next one. Plain data,
// so that a checkpoint can store it (the pebble game itself is rebuilt after a restore).
struct RigidityMemory {
  bool has_state = false;
  bool spanned = false;  // the first spanning cluster has been reported
  long floppy_plane = 0;
  long span_code = 0;                                        // spans_x + 2·spans_y
  std::vector<std::pair<std::int64_t, std::uint8_t>> cells;  // sorted by id: bit 0 in largest, bit 1 bud rigid
};

// How the tracker handles contacts that disappear. `retest`: remove them from the pebble state
// (free for a redundant bar) and re-test the redundant bars once if an independent one left.
// `rebuild`: replay the whole game (the reference, to compare costs).
enum class RemovalPolicy { retest, rebuild };

// Keeps a pebble game current across successive states of one growing packing. Invariant: the
// game's bars are exactly the framework of the last state, in `keys_` order.
class RigidityTracker {
 public:
  explicit RigidityTracker(RigidityNetwork which = RigidityNetwork::load_bearing,
                           RemovalPolicy policy = RemovalPolicy::retest);

  // Brings the game to the new state — insertions only are played incrementally, the cell count
  // may grow (joints are appended) — and returns the changes since the previous state. The first
  // call sets the baseline: it reports the floppy-mode count and spanning, no per-cell events.
  const std::vector<RigidityEvent>& update(const Packing& p, const Lobes& lobes, const std::vector<Contact>& contacts,
                                           const ContactNetwork& net);

  const RigidityState& state() const { return state_; }
  const RigidityUpdate& last_update() const { return last_; }
  const std::vector<RigidityEvent>& events() const { return events_; }
  const PebbleGame& game() const { return game_; }
  bool has_spanned() const { return memory_.spanned; }

  const RigidityMemory& memory() const { return memory_; }
  // Continue from a remembered state (e.g. after --resume): the next update replays the game
  // and reports the changes since `memory`.
  void restore(const RigidityMemory& memory);

 private:
  void rebuild(const Framework& fw, const std::vector<std::uint64_t>& keys, const Lobes& lobes, const Box& box);
  void diff_events(const Packing& p);

  RigidityNetwork which_;
  RemovalPolicy policy_;
  PebbleGame game_;
  bool game_current_ = false;        // the game holds the framework of the last state
  std::vector<std::uint64_t> keys_;  // (a << 32) | b of every game bar
  RigidityState state_;
  RigidityMemory memory_;
  std::vector<RigidityEvent> events_;
  RigidityUpdate last_;
};

}  // namespace budjam
