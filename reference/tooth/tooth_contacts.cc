#include "reference/tooth/tooth_contacts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "reference/core/io.h"

namespace dentsim {

std::uint8_t heaviest_material(std::span<const Contact> contacts) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < contacts.size(); ++i) {
    if (contacts[i].weight > contacts[best].weight) best = i;
  }
  return contacts[best].material;
}

ContactModel parse_contact_model(const std::string& name) {
  if (name == "faces") return ContactModel::kFaces;
  if (name == "sdf") return ContactModel::kSurfaceProxy;
  if (name == "field") return ContactModel::kField;
  throw InputError("contact model '" + name +
                   "': expected \"sdf\" (the default), \"faces\" or \"field\"");
}

const char* contact_model_name(ContactModel model) {
  if (model == ContactModel::kField) return "field";
  return model == ContactModel::kFaces ? "faces" : "sdf";
}

ToothProviderBase::ToothProviderBase(const VoxelGrid& grid, ToolTip tip, double k_tooth,
                                     double b_tooth, const DrillParams* drill)
    : tip_(tip), k_tooth_(k_tooth), b_tooth_(b_tooth) {
  validate_tool_tip(tip_);
  if (drill != nullptr) {
    validate_drill_params(*drill);
    drills_ = true;
    drill_params_ = *drill;
    drill_state_ = make_drill_state(grid);
    drill_log_.reserve(kDrillLogCapacity);
  }
  voxels_.reserve(kContactCapacity);
  removed_.reserve(kContactCapacity);
}

void ToothProviderBase::prefault_drill_log(std::size_t records) {
  if (!drill_log_.empty()) return;  // the appended records are the run's
  drill_log_.resize(std::min(records, drill_log_.capacity()));
  drill_log_.clear();
}

std::size_t ToothProviderBase::begin_query(std::vector<Contact>& out) {
  ++ticks_;
  out.clear();
  voxels_.clear();
  removed_.clear();
  return std::min(out.capacity(), voxels_.capacity());
}

ToothContactProvider::ToothContactProvider(VoxelTooth& tooth, ToolTip tip, double k_tooth,
                                           double b_tooth, const DrillParams* drill,
                                           ContactModel model, SignedDistanceFn sd,
                                           SampledField* field)
    : ToothProviderBase(tooth.grid(), tip, k_tooth, b_tooth, drill),
      tooth_(tooth),
      model_(model),
      surface_(tip.radius, tooth.grid().voxel_size, sd),
      sd_(sd) {
  if (model_ == ContactModel::kField) {
    if (field == nullptr) throw InputError("contact model \"field\": no field of the tooth given");
    if (drill != nullptr) {
      // Room for the bricks the cut opens below the band (field_contact.md §5): half the band's
      // bricks again, at least 256 (0.5 MB).
      field->reserve_spare_bricks(std::max<std::size_t>(256, field->brick_count() / 2));
      edited_field_ = field;
      edit_queue_.assign(kFieldEditQueue, 0);
    }
    field_ = std::make_unique<FieldSolid>(tooth, *field);
    sampled_field_ = field;
  }
  drill_contacts_.reserve(kContactCapacity);
  drill_voxels_.reserve(kContactCapacity);
  if (drill != nullptr && model_ != ContactModel::kFaces) {
    scratch_.candidates.reserve(cut_candidates_capacity(tooth.grid(), tip.radius));
  }
}

std::size_t ToothContactProvider::cut_candidates_capacity(const VoxelGrid& grid, double rho) {
  // collect_cut_set's query lists every solid voxel whose cube meets the ball of radius
  // r = cut_band(rho).reach about g: their centres lie within r + h sqrt(3) / 2 of g, so
  // at most (2 floor(r / h + sqrt(3) / 2) + 1)^3 of them (and no more than the grid's). Room for
  // all, so that the query never grows the vector in the tick (a wide bur on a fine grid holds
  // far more than the scratch's default 4096: ~8 000 solid voxels for the 0.5 mm bur at 512^3).
  const double h = grid.voxel_size;
  const double r = cut_band(rho).reach;
  const double across = 2.0 * std::floor(r / h + 0.5 * std::sqrt(3.0)) + 1.0;
  const double n = static_cast<double>(grid.n);
  return static_cast<std::size_t>(std::min(across * across * across, n * n * n));
}

bool ToothContactProvider::contacts(const Pose& proxy, std::vector<Contact>& out) {
  const std::size_t max_contacts = begin_query(out);
  if (model_ == ContactModel::kFaces) {
    return collide_tool_tip(tooth_, proxy, tip_, k_tooth_, b_tooth_, &scratch_, &out, &voxels_,
                            max_contacts);
  }
  drill_contacts_.clear();
  drill_voxels_.clear();
  have_cut_ = false;
  if (field_edit_latency_ > 0) {
    publish_field_edits(ticks_);  // the cut of tick ticks_ - L (fixed latency)
  } else if (edit_count_ > 0) {
    edit_queued_voxels();  // the field follows the last ticks' cuts (bounded)
  }
  const Vec3 c = proxy.x + proxy.R * tip_.offset_body;
  const Vec3& g = model_ == ContactModel::kField ? update_field_proxy(&surface_, c)
                                                 : update_sdf_proxy(&surface_, c);
  Contact contact;  // surface_proxy_contact, its material from surface_contact_voxels
  if (!surface_proxy_geometry(proxy, tip_, g, &contact)) {
    measure_anchor(c, g, false);
    return true;
  }
  measure_anchor(c, g, true);
  if (out.capacity() < 1) return false;
  // The material, and the voxels in the bur's cutting band about g by the band's depth
  // (drilling.h collect_cut_set).
  // At a fixed latency (drills_late()), the material only: the cut is done L ticks later.
  const bool late = drills_late();
  surface_contact_voxels(g, &contact, drills_ && !late ? &drill_contacts_ : nullptr,
                         &drill_voxels_);
  if (late) {
    have_cut_ = true;
    late_cut_.tick = ticks_;
    late_cut_.g = g;
    late_cut_.contact = contact;
  }
  out.push_back(contact);
  return true;
}

void ToothContactProvider::surface_contact_voxels(const Vec3& g, Contact* contact,
                                                  std::vector<Contact>* shares,
                                                  std::vector<std::size_t>* voxels) {
  set_contact_material(proxy_material(tooth_, g, tip_.radius, sd_), k_tooth_, b_tooth_, contact);
  if (shares == nullptr) return;
  collect_cut_set(tooth_, *contact, g, tip_.radius, &scratch_.candidates, shares, voxels);
}

const Vec3& ToothContactProvider::update_field_proxy(SurfaceProxy* proxy, const Vec3& c) {
  return proxy->update(*field_, c);
}

const Vec3& ToothContactProvider::update_sdf_proxy(SurfaceProxy* proxy, const Vec3& c) {
  return proxy->update(tooth_, c);
}

bool ToothContactProvider::edit_field(SampledField* field, std::span<const std::size_t> removed,
                                      FieldEditStats* stats, FieldEditCursor* cursor,
                                      long budget) {
  return edit_field_for_removed_voxels(field, tooth_, removed, sd_, stats, cursor, budget);
}

void ToothContactProvider::edit_queued_voxels() {
  // The ring's queued voxels in at most two contiguous runs (before and after its end), the
  // second with what the first left of the budget. A call that finishes its run had spent less
  // than its budget at its last step's start, and the second is begun only with more than a
  // voxel's set-up left, so the two spend at most max(budget - 1, kFieldEditVoxelWeight) +
  // field_edit_step_work(R) together (field_edit_core.h).
  const std::size_t capacity = edit_queue_.size();
  long left = field_edit_budget_;
  while (edit_count_ > 0 && left > 0) {
    const std::size_t run = std::min(edit_count_, capacity - edit_head_);
    const long work_before = field_edits_.work;
    edit_cursor_.next = 0;  // the run starts at the queue's head (edit_cursor_.row: where in it)
    if (!edit_field(edited_field_, std::span<const std::size_t>(&edit_queue_[edit_head_], run),
                    &field_edits_, &edit_cursor_, left)) {
      ++field_edit_shortfalls_;
    }
    const std::size_t done = edit_cursor_.next;  // voxels finished; the next one may be begun
    edit_cursor_.next = 0;
    edit_head_ = (edit_head_ + done) % capacity;
    edit_count_ -= done;
    if (done < run) break;  // paused inside the run: the budget is spent
    left -= field_edits_.work - work_before;
    // The second run's first row is begun whatever is left (field_edit_core.h): only with room
    // for its voxel's set-up below the budget, so the bound above holds.
    if (left <= kFieldEditVoxelWeight) break;
  }
  if (edit_count_ == 0) edit_head_ = 0;
}

void ToothContactProvider::set_field_edit_rate(double samples_per_second) {
  if (!(samples_per_second > 0.0)) {
    throw InputError("field edit rate " + std::to_string(samples_per_second) +
                     " units of work/s: expected > 0 (+inf: no budget)");
  }
  field_edit_rate_ = samples_per_second;
}

void ToothContactProvider::set_field_edit_queue(std::size_t capacity) {
  if (capacity < 1 || edit_count_ > 0) {
    throw InputError("field edit queue of " + std::to_string(capacity) +
                     " voxels: expected >= 1, set before any voxel is queued");
  }
  if (edited_field_ != nullptr) edit_queue_.assign(capacity, 0);
  edit_head_ = 0;
  field_batch_limit_ = capacity;
}

void ToothContactProvider::sort_field_batch(std::size_t* first, std::size_t* last) const {
  sort_by_field_box(first, last, tooth_.grid().n,
                    edited_field_ != nullptr ? edited_field_->stride() : 1);
}

void ToothContactProvider::sort_by_field_box(std::size_t* first, std::size_t* last, int grid_n,
                                             int k) {
  // At stride k > 1, a tick's voxels in the order of their boxes' centres floor(c / k), so that
  // the edit subtracts the voxels of one coarse cell together (the batch, field_edit_core.h). In
  // place: std::sort allocates nothing.
  if (k <= 1 || last - first < 2) return;
  const std::size_t n = static_cast<std::size_t>(grid_n);
  const std::size_t nk = n / static_cast<std::size_t>(k) + 1;
  const auto key = [n, nk, k](std::size_t v) {
    const std::size_t kk = static_cast<std::size_t>(k);
    return (v % n) / kk + nk * (((v / n) % n) / kk + nk * ((v / (n * n)) / kk));
  };
  std::sort(first, last, [&key](std::size_t a, std::size_t b) { return key(a) < key(b); });
}

void ToothContactProvider::set_field_edit_latency(int ticks) {
  if (ticks < 0 || ticks_ > 0 || edit_count_ > 0) {
    throw InputError("field edit latency of " + std::to_string(ticks) +
                     " ticks: expected >= 0 (0: the budget path), set before the first tick");
  }
  if (edited_field_ == nullptr) return;  // no kField drilling: nothing is edited
  field_edit_latency_ = ticks;
  if (ticks > 0) prepare_field_latency(ticks);
}

void ToothContactProvider::prepare_field_latency(int ticks) {
  // The cuts not yet done, oldest first: L of them when contacts() runs every tick (one more of
  // room).
  field_batches_.assign(static_cast<std::size_t>(ticks) + 1, FieldBatch{});
  for (FieldBatch& b : field_batches_) b.voxels.reserve(kFieldEditQueue);
}

void ToothContactProvider::hand_off_field_cut(const FieldDrillCut& cut) {
  if (field_batch_count_ == field_batches_.size()) {  // never grow in the tick: not cut
    ++field_edit_shortfalls_;
    return;
  }
  field_batches_[(field_batch_head_ + field_batch_count_) % field_batches_.size()].cut = cut;
  ++field_batch_count_;
}

void ToothContactProvider::publish_field_edits(long tick) {
  // Every cut of tick <= tick - L, in tick order (one, the cut of tick - L, when contacts() runs
  // every tick), while last_removed() has room for a whole cut set.
  while (field_batch_count_ > 0 &&
         field_batches_[field_batch_head_].cut.tick <= tick - field_edit_latency_ &&
         removed_.size() + drill_contacts_.capacity() <= removed_.capacity()) {
    FieldBatch& b = field_batches_[field_batch_head_];
    // The drilling of tick b.cut.tick on the grid as the earlier cuts left it (drill()'s, then).
    drill_contacts_.clear();
    drill_voxels_.clear();
    collect_cut_set(tooth_, b.cut.contact, b.cut.g, tip_.radius, &scratch_.candidates,
                    &drill_contacts_, &drill_voxels_);
    if (!drill_contacts_.empty()) {
      const std::array<std::int64_t, kMaterialCount> removed_before =
          drill_state_.removed_voxels;
      const bool pulp_before = drill_state_.pulp_exposed;
      const std::uint8_t material = heaviest_material(drill_contacts_);
      const std::size_t first = removed_.size();
      drill_tick(drill_contacts_, drill_voxels_, tip_, drill_params_, b.cut.T, &tooth_,
                 &drill_state_, &removed_);
      record_drill_at(b.cut.tick, b.cut.surface_z, b.cut.force_n, material, removed_before,
                      pulp_before);
      // The batch: the removed voxels (at most the limit) sorted by box, subtracted from the
      // field on the grid right after their removal.
      const std::size_t count = removed_.size() - first;
      const std::size_t fit = std::min({count, field_batch_limit_, b.voxels.capacity()});
      b.voxels.assign(removed_.begin() + static_cast<std::ptrdiff_t>(first),
                      removed_.begin() + static_cast<std::ptrdiff_t>(first + fit));
      field_edit_shortfalls_ += static_cast<long>(count - fit);
      sort_field_batch(b.voxels.data(), b.voxels.data() + b.voxels.size());
      if (!b.voxels.empty() &&
          !edit_field_for_removed_voxels(edited_field_, tooth_, b.voxels, sd_, &field_edits_)) {
        ++field_edit_shortfalls_;
      }
    }
    drill_contacts_.clear();
    drill_voxels_.clear();
    if (b.cut.tick < tick - field_edit_latency_) ++field_edit_late_publishes_;
    field_batch_head_ = (field_batch_head_ + 1) % field_batches_.size();
    --field_batch_count_;
  }
}

double ToothContactProvider::field_value(const Vec3& x) const {
  return sampled_field_ != nullptr ? sampled_field_->value(x) : 0.0;
}

void ToothContactProvider::measure_anchor(const Vec3& c, const Vec3& g, bool in_contact) {
  anchored_.center = tip_.offset_body;
  if (!in_contact) {
    anchored_.held = 0.0;
  } else if (have_last_) {
    const Vec3 n = (g - c).normalized();
    const Vec3 dc = c - c_last_;
    const Vec3 dg = g - g_last_;
    const Vec3 dc_t = dc - n.dot(dc) * n;
    const Vec3 dg_t = dg - n.dot(dg) * n;
    const double moved2 = dc_t.squaredNorm();
    // g is found to the proxy's tolerance (1e-9 rho): a motion across n of 1e-6 rho or less
    // (0.4 nm per tick for a 0.4 mm tip) says nothing about the anchor; h is kept.
    const double still = 1e3 * surface_.constants().tol;
    if (moved2 > still * still) {
      anchored_.held = std::clamp(1.0 - dg_t.dot(dc_t) / moved2, 0.0, 1.0);
    }
  }
  have_last_ = true;
  c_last_ = c;
  g_last_ = g;
}

int ToothContactProvider::drill(std::span<const Contact> contacts, double T) {
  if (!drills_ || contacts.empty()) return 0;
  const std::array<std::int64_t, kMaterialCount> removed_before = drill_state_.removed_voxels;
  const bool pulp_before = drill_state_.pulp_exposed;
  int removed = 0;
  std::uint8_t material = kEmpty;  // the material under the bur: the heaviest cut share's
  if (model_ != ContactModel::kFaces) {  // the surface proxy on the voxels or on the field
    if (drills_late()) {  // the cut is done L ticks later (publish_field_edits)
      if (!have_cut_) return 0;
      have_cut_ = false;
      late_cut_.T = T;
      drill_record_figures(contacts, &late_cut_.surface_z, &late_cut_.force_n);
      hand_off_field_cut(late_cut_);
      return static_cast<int>(removed_.size());  // the voxels this tick's publish removed
    }
    if (drill_contacts_.empty()) return 0;
    material = heaviest_material(drill_contacts_);
    removed = drill_tick(drill_contacts_, drill_voxels_, tip_, drill_params_, T, &tooth_,
                         &drill_state_, &removed_);
    drill_contacts_.clear();
    drill_voxels_.clear();
    if (edited_field_ != nullptr) {  // queued for the next contacts() calls
      // The next calls' budget, from this tick's length (header: budget(T)).
      const double budget = field_edit_rate_ * T;
      field_edit_budget_ = budget >= 1e15 ? std::numeric_limits<long>::max()
                                          : std::max(1L, static_cast<long>(budget));
      const std::size_t capacity = edit_queue_.size();
      const std::size_t first = (edit_head_ + edit_count_) % capacity, count_before = edit_count_;
      for (const std::size_t v : removed_) {
        if (edit_count_ < capacity) {
          edit_queue_[(edit_head_ + edit_count_) % capacity] = v;
          ++edit_count_;
        } else {
          ++field_edit_shortfalls_;  // never grow in the tick: that voxel stays in the field
        }
      }
      // At stride k > 1, this tick's voxels in the order of their boxes' centres floor(c / k),
      // so that the edit subtracts the voxels of one coarse cell together (the batch,
      // field_edit_core.h). In place (std::sort allocates nothing), each contiguous piece of
      // the ring; the voxels queued before keep their order (a paused group among them).
      if (edit_count_ > count_before) {
        const std::size_t added = edit_count_ - count_before;
        const std::size_t piece = std::min(added, capacity - first);
        sort_field_batch(edit_queue_.data() + first, edit_queue_.data() + first + piece);
        sort_field_batch(edit_queue_.data(), edit_queue_.data() + (added - piece));
      }
    }
  } else {
    if (!can_drill(contacts)) return 0;
    material = heaviest_material(contacts);
    removed =
        drill_tick(contacts, voxels_, tip_, drill_params_, T, &tooth_, &drill_state_, &removed_);
  }
  record_drill(contacts, material, removed_before, pulp_before);
  return removed;
}

void ToothProviderBase::drill_record_figures(std::span<const Contact> contacts,
                                             double* surface_z, double* force_n) {
  std::size_t heaviest = 0;
  for (std::size_t i = 1; i < contacts.size(); ++i) {
    if (contacts[i].weight > contacts[heaviest].weight) heaviest = i;
  }
  *surface_z = contacts[heaviest].x_o.z();
  double total_weight = 0.0;
  Vec3 f = Vec3::Zero();
  for (const Contact& ct : contacts) {
    total_weight += ct.weight;
    f += ct.weight * ct.stiffness * ct.depth * ct.n;
  }
  *force_n = total_weight > 0.0 ? f.norm() / total_weight : 0.0;
}

void ToothProviderBase::record_drill(std::span<const Contact> contacts, std::uint8_t material,
                                     const std::array<std::int64_t, kMaterialCount>& removed_before,
                                     bool pulp_before) {
  double z = 0.0, force = 0.0;
  drill_record_figures(contacts, &z, &force);
  record_drill_at(ticks_, z, force, material, removed_before, pulp_before);
}

void ToothProviderBase::record_drill_at(
    long tick, double z, double force_n, std::uint8_t material,
    const std::array<std::int64_t, kMaterialCount>& removed_before, bool pulp_before) {
  if (drill_state_.pulp_exposed && !pulp_before) pulp_exposed_tick_ = tick;
  if (drill_log_.size() >= drill_log_.capacity()) return;  // full: never grow in the tick
  DrillRecord rec;
  rec.tick = tick;
  if (!have_surface_z_) {
    have_surface_z_ = true;
    first_surface_z_ = z;
  }
  rec.depth_m = first_surface_z_ - z;
  rec.force_n = force_n;
  rec.material = material;
  for (int m = 0; m < kMaterialCount; ++m) {
    rec.removed[m] = static_cast<int>(drill_state_.removed_voxels[m] - removed_before[m]);
  }
  drill_log_.push_back(rec);
}

std::unique_ptr<PipelineTooth> make_reference_tooth(VoxelTooth& tooth,
                                                    const PipelineToothSetup& setup) {
  auto t = std::make_unique<ProviderTooth<ToothContactProvider>>(
      tooth, setup, tooth, setup.tip, setup.k_tooth, setup.b_tooth, setup.drilling,
      setup.contact_model, &signed_distance, setup.field);
  // The field model's edit at the same fixed latency as the fast pipeline's (applied here in one
  // step at the start of tick t + L; ignored without field drilling), so that both pipelines run
  // the same model and the reference's edit never falls behind a fine grid's cut.
  if (setup.field_edit_latency > 0) {
    static_cast<ToothContactProvider&>(t->provider())
        .set_field_edit_latency(setup.field_edit_latency);
  }
  return t;
}

const AnchoredSpring* anchored_spring(const ContactProvider* env) {
  // The surface-proxy contact renders a spring to an anchor (reference/contact.h); the face
  // model's force stays along the face normal. A pointer cast: no allocation, no throw.
  const auto* tooth = dynamic_cast<const ToothContactProvider*>(env);
  if (tooth == nullptr || tooth->model() == ContactModel::kFaces) return nullptr;
  return &tooth->anchored_spring();
}

}  // namespace dentsim
