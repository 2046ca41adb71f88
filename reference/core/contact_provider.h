// The collision stage as the servo tick sees it (docs/design.md "The tick as Model/Data stages"):
// an environment that reports the contact set of the tool at the proxy pose, and that the tool
// may cut (drilling). Implementations: the voxel tooth (reference/tooth/tooth_contacts.h), the
// half-space wall (reference/half_space_wall.h), free space (NoContacts).
//
// Real-time contract: contacts() and drill() run inside the servo tick, so they never allocate
// and never throw. `out` is the tick's fixed-capacity contact buffer: an implementation fills it
// (cleared first) without growing it beyond its capacity and returns false when the set did not
// fit (the tick then reports kContactBufferFull and the loop owner stops the device).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

// Capacity of the tick's contact buffer (PipelineData): a 0.8 mm bur on a 256^3 molar reports
// about 250 members; a set that does not fit stops the device (kContactBufferFull).
inline constexpr std::size_t kContactCapacity = 4096;

class ContactProvider {
 public:
  virtual ~ContactProvider() = default;
  // The contacts of the tool at `proxy` (the tool-tip frame x_2, R_2). Returns false when the set
  // did not fit into out.capacity() (out then holds the first capacity() members).
  virtual bool contacts(const Pose& proxy, std::vector<Contact>& out) = 0;
  // Whether the tool cuts this environment (the tick's `drill` stage runs only then).
  virtual bool drills() const { return false; }
  // The tool's cut over a tick of length T [s], from the contact set this provider returned last
  // (the tick's). Returns the number of voxels removed.
  virtual int drill(std::span<const Contact> contacts, double T) {
    (void)contacts;
    (void)T;
    return 0;
  }
  // Whether the cut's per-voxel work store ran out of room (sticky): the tick then reports
  // kDrillWorkTableFull and the loop owner stops the device (reference/tooth/voxel_work.h).
  virtual bool drill_store_full() const { return false; }
  // Whether the field model's drilling edit fell short (sticky): a removed voxel found no room in
  // the edit queue, or a sample no spare brick, so the field keeps material the voxels lost for
  // good. The tick then reports kFieldEditShortfall and the loop owner stops the device
  // (reference/tooth/tooth_contacts.h; why a fault: docs/derivations/field_contact.md §6).
  virtual bool field_edit_shortfall() const { return false; }
};

// A provider with no contacts (free space).
class NoContacts : public ContactProvider {
 public:
  bool contacts(const Pose&, std::vector<Contact>& out) override {
    out.clear();
    return true;
  }
};

}  // namespace dentsim
