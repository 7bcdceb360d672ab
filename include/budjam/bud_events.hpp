#pragma once
// Survival of the buds that are unconstrained at jamming (docs/model.md, "Bud events and survival").
// At jamming every unconstrained bud is tagged (by cell id); from then on, for each accepted state,
// a tagged bud can: touch something for the first time (first_contact), stop being unconstrained
// (completed: the event of the Kaplan–Meier estimate), divide before completion (censored), or
// still be unconstrained when the run ends or the next jamming tags others (censored). After an
// unjamming the tags are followed on until that next jamming, as the paper's code follows them.
// a = b² − b_J² is the added bud size in diameter squared (true area π a / 4).
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>
#include "budjam/contact_network.hpp"
#include "budjam/contacts.hpp"
#include "budjam/growth.hpp"
#include "budjam/packing.hpp"

namespace budjam {

enum class BudEventKind {
  tagged,          // unconstrained at jamming (a = 0)
  first_contact,   // its bud lobe carries a contact for the first time (any contact, also with rattlers)
  completed,       // no longer unconstrained (event)
  divided,         // the cell divided before completion (censored)
  censored_end,    // still unconstrained when the run ended (censored)
  censored_unjam,  // its episode unjammed, and still unconstrained when the packing jammed again (censored)
};
const char* to_string(BudEventKind kind);

struct BudEvent {
  BudEventKind kind = BudEventKind::tagged;
  int episode = 0;  // jamming episode
  std::int64_t cell_id = -1;
  long step = 0;  // accepted-step index
  double phi = 0;
  double a = 0;  // b² − b_J²
};

class BudTracker {
 public:
  // Tags every unconstrained bud of `net` (non-rattler, bud lobe with no load-bearing contact).
  // Replaces any previous tags. Returns the `tagged` events (in cell-index order).
  std::vector<BudEvent> tag(int episode, long step, double phi, const Packing& p, const ContactNetwork& net);

  // Updates the active tags after an accepted state. `divisions` happened in the step that produced
  // this state: a tagged cell among them ends as `divided` with a taken at division. Returns the
  // events in cell-id order (first_contact before completed for the same bud).
  std::vector<BudEvent> update(long step, double phi, const Packing& p, const std::vector<Contact>& contacts,
                               const ContactNetwork& net, const std::vector<Division>& divisions);

  // Ends every active tag with `kind` (censored_end or censored_unjam).
  std::vector<BudEvent> close(BudEventKind kind, long step, double phi, const Packing& p);

  std::size_t tagged() const { return tags_.size(); }
  std::size_t active() const;  // tagged, neither completed nor divided nor closed
  std::size_t completed() const;
  std::size_t divided() const;
  std::size_t touched() const;  // had their first contact
  // The events tag, update and close have returned for the current tags: one `tagged` each, one
  // `first_contact` for each that touched, one end (completed, divided or censored) for each
  // no longer active.
  std::size_t events() const { return 2 * tagged() + touched() - active(); }
  int episode() const { return episode_; }
  // Those events of the tag of cell `id`, in the order they were returned ("censored" for a closed tag,
  // whichever kind closed it); empty for a cell without a tag.
  std::vector<std::string> events_of(std::int64_t id) const;
  std::vector<std::int64_t> tagged_ids() const;

  void save(std::ostream& os) const;
  void load(std::istream& is);

 private:
  struct Tag {
    std::int64_t id;
    double b2_J;
    bool touched = false;
    int state = 0;  // 0 active, 1 completed, 2 divided, 3 closed
  };
  std::vector<Tag> tags_;  // sorted by id
  int episode_ = 0;
};

}  // namespace budjam
