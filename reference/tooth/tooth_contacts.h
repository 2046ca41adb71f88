// The voxel tooth as the tick's collision and drilling stages: a ContactProvider
// (reference/core/contact_provider.h) with two contact models (scene key tooth.contact_model):
// - kFaces ("faces", the thesis): collide_tool_tip (reference/tooth/collision.h);
// - kSurfaceProxy ("sdf", beyond the thesis, the scenes' default): the surface proxy on the exact
//   signed distance of reference/tooth/sdf.h, one contact between the tool's sphere and the proxy.
// The constructor defaults to kFaces (validation/zwidth.cc renders its wall with it); scenes
// default to "sdf" (sim/scene.h).
// It keeps the voxels of the last query so that drilling (reference/tooth/drilling.h) can run on
// the same set after the solve: for kFaces the voxel of every contact; for kSurfaceProxy and
// kField the exposed solid voxels in the bur's cutting band about the proxy centre g (drilling.h
// collect_cut_set; docs/derivations/drilling.md §5), each sharing the contact's force by the
// band's depth at its middle.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "reference/contact.h"
#include "reference/core/contact_provider.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/drilling.h"
#include "reference/tooth/field_contact.h"
#include "reference/tooth/sdf.h"

namespace dentsim {

enum class ContactModel { kFaces, kSurfaceProxy, kField };

// "faces" / "sdf" / "field" (reference/tooth/field_contact.h); throws InputError naming the value
// otherwise.
ContactModel parse_contact_model(const std::string& name);
const char* contact_model_name(ContactModel model);

// One drilling tick as the provider saw it (for the drill plot and report.json).
struct DrillRecord {
  long tick = 0;         // 1-based index of the contacts() call (the servo tick)
  double depth_m = 0.0;  // how far the cut surface point x_o is below the first one's (world z)
  double force_n = 0.0;  // |blended penalty force| of the tick's set
  std::uint8_t material = 0;                  // material under the bur (the heaviest cut share's)
  std::array<int, kMaterialCount> removed{};  // voxels removed this tick per material
};

// Capacity of the drill log (preallocated; recording stops when full): 2 min at 1 kHz.
inline constexpr std::size_t kDrillLogCapacity = 120000;

// What the drilling of one servo tick needs when it runs L ticks later (the field model at a fixed
// edit latency, ToothContactProvider::set_field_edit_latency): the tick, the proxy centre g and
// the contact as contacts() built it (its material and stiffness), the tick's length T, and the
// drill log's figures of the tick's solved contact set (record_drill: the heaviest member's cut
// surface height and the blended force).
struct FieldDrillCut {
  long tick = 0;
  Vec3 g = Vec3::Zero();
  Contact contact;
  double T = 0.0;
  double surface_z = 0.0;
  double force_n = 0.0;
};

// What the reference and the fast tooth providers (fast/tooth/tooth_contacts.h) share: the tip,
// the scene's stiffness and damping, the drill parameters and state, the voxel index of each
// contact of the last query, and the drill log. The constructor validates the tip and the drill
// parameters (InputError) and sizes the buffers, so the tick itself neither throws nor allocates.
class ToothProviderBase : public ContactProvider {
 public:
  bool drills() const override { return drills_; }
  bool drill_store_full() const override { return drill_state_.work_table_full; }
  // Flat voxel index of each contact of the last query (parallel to its contact set).
  const std::vector<std::size_t>& contact_voxels() const { return voxels_; }
  const ToolTip& tip() const { return tip_; }
  const DrillState& drill_state() const { return drill_state_; }
  // Drilling ticks so far (empty unless the tool drills), and the tick (1-based contacts() call)
  // whose drilling first opened the pulp (0: not yet; DrillState::pulp_exposed).
  const std::vector<DrillRecord>& drill_log() const { return drill_log_; }
  long pulp_exposed_tick() const { return pulp_exposed_tick_; }
  // The flat indices of the voxels the last tick's drilling removed (empty if none).
  const std::vector<std::size_t>& last_removed() const { return removed_; }
  // Setup only (not in the tick), with the log empty: writes the first min(records, capacity)
  // entries of the drill log's storage and empties the log again (no allocation), so that the
  // ticks that append them take no first-touch page fault (one every 85 records on 4 KiB pages,
  // 10-20 us each on a virtual machine: the tail of an 8 kHz tick, docs/benchmarks.md "p99x50").
  // A run that knows its length touches only the records it can append.
  void prefault_drill_log(std::size_t records);

 protected:
  // `grid`: the tooth's grid (sizes the drill state when `drill` is set).
  ToothProviderBase(const VoxelGrid& grid, ToolTip tip, double k_tooth, double b_tooth,
                    const DrillParams* drill);
  // Counts the tick, clears `out` and the voxel list; returns the most members the query may
  // report (the smaller capacity of the two, which never grow).
  std::size_t begin_query(std::vector<Contact>& out);
  // Whether drill() has a set to cut: drilling on and `contacts` the last query's nonempty set.
  bool can_drill(std::span<const Contact> contacts) const {
    return drills_ && !contacts.empty() && contacts.size() == voxels_.size();
  }
  // Appends the tick to the drill log (never beyond its capacity) and notes the pulp's opening.
  void record_drill(std::span<const Contact> contacts, std::uint8_t material,
                    const std::array<std::int64_t, kMaterialCount>& removed_before,
                    bool pulp_before);
  // The same for the drilling of tick `tick` done later (FieldDrillCut: `surface_z` and `force_n`
  // from drill_record_figures of that tick's contacts).
  void record_drill_at(long tick, double surface_z, double force_n, std::uint8_t material,
                       const std::array<std::int64_t, kMaterialCount>& removed_before,
                       bool pulp_before);
  // The heaviest member's cut surface height x_o.z and |blended penalty force| of a nonempty set.
  static void drill_record_figures(std::span<const Contact> contacts, double* surface_z,
                                   double* force_n);

  ToolTip tip_;
  double k_tooth_, b_tooth_;
  bool drills_ = false;
  DrillParams drill_params_;
  DrillState drill_state_;
  std::vector<std::size_t> voxels_;
  std::vector<std::size_t> removed_;  // voxels removed by the last drill()
  long ticks_ = 0;                    // contacts() calls
  long pulp_exposed_tick_ = 0;
  bool have_surface_z_ = false;
  double first_surface_z_ = 0.0;
  std::vector<DrillRecord> drill_log_;
};

// The material under the bur: the heaviest member's.
std::uint8_t heaviest_material(std::span<const Contact> contacts);

class ToothContactProvider : public ToothProviderBase {
 public:
  // `tooth` must outlive the provider (drilling changes it); k_tooth [N/m] and b_tooth [N s/m]
  // are the scene's stiffness and damping (scaled per material by the collision stage). With
  // `drill` set the tool cuts the tooth (DrillParams validated here: InputError). Throws
  // InputError for a non-positive or non-finite tip radius. `sd`: the signed-distance query of the
  // surface proxy (kSurfaceProxy): the reference's, or the fast pipeline's twin
  // (fast::signed_distance, fast/tooth/sdf.h). kField: the surface proxy on `field` (the tooth's
  // sampled field, reference/tooth/field_contact.h; it must outlive the provider); InputError if
  // it is missing. With drilling on, the voxels are cut as for kSurfaceProxy and the field follows
  // them (edit_field_for_removed_voxels; the constructor reserves the field's spare bricks).
  ToothContactProvider(VoxelTooth& tooth, ToolTip tip, double k_tooth, double b_tooth,
                       const DrillParams* drill = nullptr,
                       ContactModel model = ContactModel::kFaces,
                       SignedDistanceFn sd = &signed_distance,
                       SampledField* field = nullptr);

  bool contacts(const Pose& proxy, std::vector<Contact>& out) override;
  int drill(std::span<const Contact> contacts, double T) override;

  ContactModel model() const { return model_; }
  // The surface proxy (kSurfaceProxy, kField; its g() is the rendered tip centre).
  const SurfaceProxy& surface_proxy() const { return surface_; }
  // The surface-proxy contact's spring across its normal (reference/contact.h, issue #32): the
  // tip centre o and the held fraction h, measured by each contacts() call from how far the
  // anchor g followed the tool's centre c across n since the last call,
  //     h = clamp(1 - (P dg)^T (P dc) / |P dc|^2, 0, 1),   P = I - n n^T,
  // kept while c barely moves across n (|P dc| <= 1e-6 rho, a thousand times the proxy's
  // tolerance), 0 out of contact.
  // A flat face: g follows c, h = 0; a held anchor (a drilled hole, a corner): h = 1; a concave
  // face of radius r_A at depth delta: delta / (r_A + delta).
  const AnchoredSpring& anchored_spring() const { return anchored_; }
  // With drilling (kSurfaceProxy, kField): the last contacts() call's cut set (collect_cut_set:
  // one force share per voxel, and the voxels' flat indices), which the next drill() cuts (and
  // clears).
  const std::vector<Contact>& cut_shares() const { return drill_contacts_; }
  const std::vector<std::size_t>& cut_voxels() const { return drill_voxels_; }
  // kField with drilling: drill() queues the voxels it removed (a ring of kFieldEditQueue), and
  // each contacts() call first subtracts queued ones from the field, spending about budget(T)
  // units of work (edit_field_for_removed_voxels with this provider's cursor: at most
  // max(budget(T) - 1, kFieldEditVoxelWeight) + field_edit_step_work(R), R =
  // SampledField::edit_radius(); a unit is a sample read, and the
  // octree queries, rows, voxels and re-measured cells are charged by their weights,
  // field_contact.h), resuming where the last call stopped, even in the middle of a removed
  // voxel's box, and advancing the queue by the voxels it finished. budget(T) = max(1, floor(rate
  // T)) units, rate = field_edit_rate() [units/s], T the tick's length (the
  // last drill() call's), so the edit's share of a tick's time is the same at every servo rate:
  // a contact tick's edit stays within its stated bound whatever the tick removed and however
  // many samples a removed voxel's edit reads (docs/derivations/field_contact.md §5 "Per tick").
  // The field lags the voxels by the queue (on the safe side: material the voxels lost, never a
  // tunnel). What the edits did so far, the queued voxels, and the edits that were incomplete for
  // want of a spare brick or a queue slot (0 in a healthy run; the field then keeps material the
  // voxels lost for good, and the tick reports kFieldEditShortfall: field_edit_shortfall()).
  const FieldEditStats& field_edits() const { return field_edits_; }
  std::size_t field_edits_pending() const { return edit_count_; }
  long field_edit_shortfalls() const { return field_edit_shortfalls_; }
  bool field_edit_shortfall() const override { return field_edit_shortfalls_ > 0; }
  // The default rate, in units of work a second (the name predates the weights: a unit is a
  // sample read, field_contact.h): 1000 units a tick at 1 kHz, 125 at 8 kHz, about 420 samples
  // a tick (1 kHz) at the measured mix of 2.38 units a sample read, against the earlier budget's
  // 500 samples; the queue keeps up with the drill scene's cutting as before
  // (docs/derivations/field_contact.md §5 "Per tick", docs/benchmarks.md "The field edit's
  // budget of work per tick").
  static constexpr double kFieldEditSamplesPerSecond = 1e6;
  static constexpr std::size_t kFieldEditQueue = 8192;
  double field_edit_rate() const { return field_edit_rate_; }
  // The work the next contacts() call's edit may spend (budget(T) above; the bound adds a step).
  long field_edit_budget() const { return field_edit_budget_; }
  // Setup only (not in the tick). The edit's rate [units of work/s]: > 0, +infinity for no
  // budget (each call subtracts every queued voxel); InputError otherwise.
  void set_field_edit_rate(double samples_per_second);
  // Setup only, with nothing queued: room for `capacity` >= 1 queued voxels (allocates; for tests
  // that force a full queue); InputError otherwise. With a latency (below), at most `capacity` of
  // a tick's removed voxels enter its batch (the rest: shortfalls).
  void set_field_edit_queue(std::size_t capacity);

  // The drilling and the edit at a fixed latency (docs/derivations/field_contact.md §8), the
  // alternative to the budget above (issue #30, stop 46: the drilling's voxel work, which grows
  // with the resolution, off the servo's tick). Tick t's contacts() solves the contact on the
  // field and reads its material from the grid, and drill() hands the tick's cut over
  // (FieldDrillCut: g, the contact, T). At the start of tick t + L's contacts() that cut is done,
  // in tick order: the cut set about g (collect_cut_set) on the grid as the cuts of the ticks
  // before t left it, the work and the removal (drill_tick: the grid, the drill state, the drill
  // log's record of tick t, the pulp's opening at tick t), and the removed voxels (the batch of
  // t, sorted by box as the queue sorts them) subtracted, all of them, from the field on the grid
  // right after that removal. So the grid and the field both show the cuts of the ticks up to
  // t - L when tick t reads them: the contact's material lags the bur by L ticks like the field,
  // and the voxels and the field lag the bur on the safe side (material the bur has earned, never
  // a tunnel). Here (the specification) the cut is done at the start of tick t + L's contacts();
  // the fast pipeline's provider does it on a worker thread, on its own copy of the grid, and
  // publishes it then (fast/tooth/field.h). kFieldEditLatency: the fast pipeline's default L (the
  // least that lets the worker overlap a servo tick: L = 1 would publish at the start of the tick
  // after the drilling, before the worker could run). The cuts of a run's last L ticks are never
  // done.
  static constexpr int kFieldEditLatency = 2;
  // Setup only (before the first contacts() call; allocates L + 1 batches of kFieldEditQueue
  // voxels): L >= 1 ticks, or 0 for the budget path (the default). Ignored without kField
  // drilling. InputError for L < 0 or after the first tick.
  void set_field_edit_latency(int ticks);
  int field_edit_latency() const { return field_edit_latency_; }
  // Batches published after their tick t + L (a real-time loop whose worker was not done: the
  // fast provider publishes at the first tick it is; 0 in simulation when contacts() runs every
  // tick).
  long field_edit_late_publishes() const { return field_edit_late_publishes_; }
  // Batches the servo edited itself because the fast provider's worker had not started them at
  // tick t + L (simulation; 0 here, where the servo applies every batch).
  long field_edit_servo_takeovers() const { return field_edit_servo_takeovers_; }
  // Batches the servo waited for at tick t + L because the fast provider's worker was editing
  // them (simulation; 0 here), and the wall time [ns] the servo spent on the takeovers and the
  // waits, from a clock read on those paths only: the worker's work done or waited for on the
  // servo's thread, which a real-time servo never does (0 here, where the servo's publish is the
  // specification's, not a stand-in; a simulated run's servo_tick leaves it out, sim/simulator.h).
  long field_edit_worker_waits() const { return field_edit_worker_waits_; }
  // Cuts whose hand-over found the fast provider's worker asleep and woke it (a futex wake on the
  // servo's thread; the rest found it editing or watching for the next cut; 0 here).
  long field_edit_worker_wakes() const { return field_edit_worker_wakes_; }
  long field_edit_stand_in_ns() const { return field_edit_stand_in_ns_; }
  // The room collect_cut_set's candidates need for a bur of radius rho on `grid` (allocated once
  // at setup, so that the query never grows them in the tick).
  static std::size_t cut_candidates_capacity(const VoxelGrid& grid, double rho);
  // sort_field_batch's order for a grid of n^3 voxels and a field of stride k (no allocation).
  static void sort_by_field_box(std::size_t* first, std::size_t* last, int grid_n, int k);
  // Setup, a real-time loop: the provider's helper thread (the fast provider's field edit
  // worker; none here) at SCHED_FIFO `priority`. Returns "" when granted or when there is no such
  // thread, else why not.
  virtual std::string set_worker_priority(int /*priority*/) { return {}; }
  // phi(x) of the field as contacts() reads it (the sampled field here; the fast twin's published
  // bricks: the same doubles, and no read of a field the worker is editing). kField only.
  virtual double field_value(const Vec3& x) const;

 protected:
  // The field model's two steps on the field, which a twin with the same results may replace
  // (the fast pipeline's, fast/tooth/field.h; neither may allocate or throw): the surface proxy's
  // update for the tip centre c on `proxy` (here: on FieldSolid), and the subtraction of
  // `removed` from `field` (here: edit_field_for_removed_voxels with this provider's query).
  virtual const Vec3& update_field_proxy(SurfaceProxy* proxy, const Vec3& c);
  // kSurfaceProxy: the surface proxy's update for the tip centre c on the voxel tooth (here:
  // SurfaceProxy::update with this provider's query), which a twin with the same results may
  // replace (the fast pipeline's, fast/tooth/tooth_contacts.h; no allocation, no throw).
  virtual const Vec3& update_sdf_proxy(SurfaceProxy* proxy, const Vec3& c);
  // The surface-proxy contact's voxel side (kSurfaceProxy, kField), once its geometry is set
  // (surface_proxy_geometry): the material of `contact` (surface_proxy_contact's: of the solid
  // voxel nearest to g within proxy_material_reach, by this provider's query) and, when `shares`
  // is not null (drilling), the cut set about g (collect_cut_set with `contact` as set here)
  // appended to `shares` and `voxels`. Here: proxy_material and collect_cut_set on the octree; a
  // twin with the same results may replace it (the fast pipeline's: fast/tooth/cut_set.h, over
  // the surface voxels; no allocation, no throw).
  virtual void surface_contact_voxels(const Vec3& g, Contact* contact,
                                      std::vector<Contact>* shares,
                                      std::vector<std::size_t>* voxels);
  // The edit takes `cursor` and `budget` as edit_field_for_removed_voxels does.
  virtual bool edit_field(SampledField* field, std::span<const std::size_t> removed,
                          FieldEditStats* stats, FieldEditCursor* cursor, long budget);
  // The fixed latency (above): set_field_edit_latency's set-up (here: the batches), drill()'s
  // hand-off of a tick's cut, and the start of contacts() at tick `tick` (here: does the cut of
  // tick - L, if any: its drilling on the grid and its edit of the field). A twin may replace the
  // three together (the fast provider's worker); the tick's two may not allocate or throw.
  virtual void prepare_field_latency(int ticks);
  virtual void hand_off_field_cut(const FieldDrillCut& cut);
  virtual void publish_field_edits(long tick);
  // Whether drilling runs L ticks late (kField drilling with a latency: above).
  bool drills_late() const { return edited_field_ != nullptr && field_edit_latency_ > 0; }
  // Sorts a tick's removed voxels in place by their boxes' centres at the field's stride (the
  // batch, field_edit_core.h; nothing at stride 1). No allocation.
  void sort_field_batch(std::size_t* first, std::size_t* last) const;
  // At most this many of a tick's removed voxels in its batch (set_field_edit_queue).
  std::size_t field_batch_limit() const { return field_batch_limit_; }
  const VoxelTooth& voxel_tooth() const { return tooth_; }

  FieldEditStats field_edits_;
  long field_edit_shortfalls_ = 0;
  long field_edit_late_publishes_ = 0;
  long field_edit_servo_takeovers_ = 0;
  long field_edit_worker_waits_ = 0;
  long field_edit_worker_wakes_ = 0;
  long field_edit_stand_in_ns_ = 0;

 private:
  void measure_anchor(const Vec3& c, const Vec3& g, bool in_contact);
  // The start of contacts() with edits queued: subtracts up to the budget's samples of them.
  void edit_queued_voxels();

  VoxelTooth& tooth_;
  CollisionScratch scratch_;
  ContactModel model_;
  SurfaceProxy surface_;
  SignedDistanceFn sd_;
  std::unique_ptr<FieldSolid> field_;  // kField
  const SampledField* sampled_field_ = nullptr;  // kField: the field field_ reads
  SampledField* edited_field_ = nullptr;  // kField with drilling: the field drill() edits
  // Removed voxels not yet subtracted: a ring, edit_count_ of them from [edit_head_]; the first
  // is subtracted in part when edit_cursor_.row > 0 (edit_cursor_.next is 0 between calls).
  std::vector<std::size_t> edit_queue_;
  std::size_t edit_head_ = 0, edit_count_ = 0;
  FieldEditCursor edit_cursor_;
  double field_edit_rate_ = kFieldEditSamplesPerSecond;
  long field_edit_budget_ = 1;
  // The fixed latency (0: the budget path), the batches not yet applied (a ring, oldest at
  // field_batch_head_), and the tooth as the applied batches left it.
  int field_edit_latency_ = 0;
  std::size_t field_batch_limit_ = kFieldEditQueue;
  struct FieldBatch {
    FieldDrillCut cut;
    std::vector<std::size_t> voxels;
  };
  std::vector<FieldBatch> field_batches_;
  std::size_t field_batch_head_ = 0, field_batch_count_ = 0;
  // The cut contacts() found for this tick's drill() (drills_late()).
  bool have_cut_ = false;
  FieldDrillCut late_cut_;
  std::vector<Contact> drill_contacts_;  // kSurfaceProxy: the drilled voxels' force shares
  std::vector<std::size_t> drill_voxels_;
  AnchoredSpring anchored_;   // the held fraction of the last contacts() call
  bool have_last_ = false;    // c_last_, g_last_ hold the last call's tip centre and anchor
  Vec3 c_last_ = Vec3::Zero();
  Vec3 g_last_ = Vec3::Zero();
};

// The tooth as one implementation of the tick holds it (fast/registry.h, Implementation::tooth):
// the contact provider its collide and drill stages use, the grid that provider drills, and the
// tool tip's face-model contact set at a pose on that grid (measurements outside the tick, e.g.
// the device tip's own penetration; the same code as the face model's collide stage).
class PipelineTooth {
 public:
  virtual ~PipelineTooth() = default;
  virtual ToothProviderBase& provider() = 0;
  virtual const VoxelGrid& grid() const = 0;
  // Clears `out` and fills it (allocation-free within its reserved capacity).
  virtual void tip_contacts(const Pose& pose, std::vector<Contact>* out) = 0;
};

// What an implementation's tooth is built from: the scene's tool tip, tooth stiffness and
// damping, drilling (null: the tool does not drill) and contact model; skip_unneeded as
// PipelineModel::skip_unneeded (an implementation may skip work the answer does not need).
struct PipelineToothSetup {
  ToolTip tip;
  double k_tooth = 0.0;
  double b_tooth = 0.0;
  const DrillParams* drilling = nullptr;
  ContactModel contact_model = ContactModel::kSurfaceProxy;
  bool skip_unneeded = true;
  // The tooth's sampled field (contact model "field"; must outlive the tooth; drilling edits it),
  // else null.
  SampledField* field = nullptr;
  // Contact model "field" with drilling: the edit's latency in ticks
  // (ToothContactProvider::set_field_edit_latency; 0: the budget path on the servo thread). The
  // fast pipeline edits on a worker thread; the reference applies each batch in one step at the
  // start of tick t + L (make_reference_tooth), so both pipelines run the same model.
  int field_edit_latency = ToothContactProvider::kFieldEditLatency;
  // The loop runs in real time (an HDAPI device, --realtime): a late field edit is published at
  // the first tick it is done instead of waited for (fast/tooth/field.h FieldEditWorker).
  bool real_time = false;
};

// A PipelineTooth around a contact provider of type Provider, built in place from
// `provider_args` (the reference's ToothContactProvider, the fast pipeline's field provider):
// the provider's grid is `tooth`'s, and tip_contacts runs the face model's collision on `tooth`
// (which must outlive it) with `setup`'s tip, stiffness and damping.
template <class Provider>
class ProviderTooth final : public PipelineTooth {
 public:
  template <class... Args>
  ProviderTooth(VoxelTooth& tooth, const PipelineToothSetup& setup, Args&&... provider_args)
      : tooth_(tooth), setup_(setup), provider_(std::forward<Args>(provider_args)...) {}

  ToothProviderBase& provider() override { return provider_; }
  const VoxelGrid& grid() const override { return tooth_.grid(); }
  void tip_contacts(const Pose& pose, std::vector<Contact>* out) override {
    out->clear();
    collide_tool_tip(tooth_, pose, setup_.tip, setup_.k_tooth, setup_.b_tooth, &scratch_, out);
  }

 private:
  VoxelTooth& tooth_;
  PipelineToothSetup setup_;
  Provider provider_;
  CollisionScratch scratch_;
};

// The reference's tooth: ToothContactProvider over `tooth` (which must outlive it), with the
// reference's signed-distance query for the surface proxy (the fast twin's is
// fast::make_fast_tooth). Throws what ToothContactProvider throws.
std::unique_ptr<PipelineTooth> make_reference_tooth(VoxelTooth& tooth,
                                                    const PipelineToothSetup& setup);

}  // namespace dentsim
