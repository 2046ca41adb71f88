// The fast twin of the "field" contact model (issue #30; reference: reference/tooth/field_contact.h
// on reference/tooth/sampled_field.h; derivation docs/derivations/field_contact.md). Same model,
// same doubles: the surface proxy (reference/tooth/surface_proxy_core.h, the same template) runs
// on fast::FieldSolid instead of dentsim::FieldSolid, and drilling's field edit is
// fast::edit_field_for_removed_voxels instead of the reference's. What changes is how the samples
// are read:
// - FieldBricks: a copy of the field's samples in bricks of 9^3 (the 8^3 of the reference's brick
//   plus one apron layer at +x, +y, +z copied from the neighbours), so that the 8 corners of any
//   cell are in one brick: one index read and 8 loads at fixed offsets per query, where the
//   reference reads the index 8 times (and 16 times, twice each, with its deep-inside test). The
//   last brick read is kept (consecutive queries of a tick, and of consecutive ticks, fall in the
//   same brick: the index is not read again). Drilling raises the reference field's samples
//   (SampledField::raise, the view and report read them) and copies each raised value into every
//   brick of the copy that holds it (FieldBricks::mirror); a slot whose brick cannot be given from
//   the copy's spare room reads through the reference field from then on (same values, slower).
// - FieldSolid (fast): one gather gives the deep-inside test, phi and its gradient; the last
//   query is kept (the proxy asks normal(x) right after distance(x) at the same x), and a
//   free-space certificate answers "phi >= reach" without reading the field (below).
// - The Lipschitz constant after an edit: the reference raises it to the cell bound of the cells
//   around each row of changed samples (SampledField::include_cells); the twin evaluates the
//   same cells from the 9^3 bricks and takes one square root at the end (sqrt and / h are
//   correctly rounded and monotone, so max_i sqrt(s_i) / h == sqrt(max_i s_i) / h exactly). The
//   twin keeps this constant itself (FieldBricks::lipschitz); the shared SampledField's own
//   lipschitz() is not raised by the fast pipeline (nothing in it reads that).
//
// Free-space certificate (FieldSolid::distance). Claim: if the last exact query (not deep inside)
// at x0 returned phi0 = phi_0(x0), L is the field's Lipschitz constant now, and
//     phi0 - L |x - x0| >= reach + margin,   reach > 0,
// then the reference's distance(x, reach) on the field now returns {phi = reach, found = false},
// so the twin returns that without reading the field. Proof: (1) phi (the trilinear interpolant,
// coordinates clamped to the lattice; clamping is 1-Lipschitz) is L_k-Lipschitz for the L_k of
// the field at the time of any query k (sampled_field.h; edits raise L to keep it a bound, and L
// never falls), and edits only raise samples (SampledField::raise is a max), so the field now is
// >= the field at query 0 everywhere: phi_now(x) >= phi_0(x) >= phi_0(x0) - L_0 |x - x0| >=
// phi0 - L |x - x0| >= reach + margin (L >= L_0). (2) phi_now(x) >= reach > 0 means x is not deep
// inside (there all 8 corners are -c_in < 0 and phi = -c_in exactly), so the reference evaluates
// the interpolant and returns reach, not found, when its computed value >= reach; the margin
// (1e-9 h, some 10^6 times the rounding of a trilinear value below 1 mm) covers the difference
// between the computed and the exact interpolant. So in free space a tick reads no sample: its
// queries (push-out, one sweep step, push-out) are answered from the last exact value while the
// tip stays farther from the surface than L times its travel since then.
//
// Real-time: queries, mirror() and the edit neither allocate nor throw.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <chrono>
#include <thread>
#include <utility>
#include <vector>

#include "fast/tooth/cut_set.h"
#include "reference/tooth/field_contact.h"
#include "reference/tooth/tooth_contacts.h"

namespace dentsim::fast {

// The field's samples in 9^3 bricks (header comment). Reads `field` (which must outlive it).
class FieldBricks {
 public:
  static constexpr int kEdge = kFieldBrick + 1;
  static constexpr int kSamples = kEdge * kEdge * kEdge;
  static constexpr std::int32_t kAllOutside = -1;
  static constexpr std::int32_t kAllInside = -2;
  static constexpr std::int32_t kViaField = -3;  // read through the reference field

  // Copies the samples of `field` and reserves room for `spare` more bricks (outside the tick).
  FieldBricks(const SampledField& field, std::size_t spare);

  const SampledField& field() const { return field_; }
  // The 8 corners of the cell with lower corner s (each in [0, m - 2]) as c[dx + 2 dy + 4 dz]
  // (SampledField::at of s + (dx, dy, dz)).
  void corners(const int s[3], float c[8]) const;
  // The stored value of sample s (SampledField::at).
  float at(int sx, int sy, int sz) const;
  // phi(x) and its gradient: SampledField::sample's arithmetic on the same samples, so bitwise
  // equal to field().sample(x) (tests/fast/field_test.cc), from one gather (corners()). When
  // `deep` is given, *deep tells whether all 8 corners are the inside clamp
  // (SampledField::deep_inside) from the same gather.
  FieldSample sample(const Vec3& x, bool* deep = nullptr) const;
  // After SampledField::raise of sample s: copies its value into every brick holding it.
  void mirror(int sx, int sy, int sz);
  // Raises lipschitz() as SampledField::include_cells does for the sample box [lo, hi].
  void include_cells(const int lo[3], const int hi[3]);
  // The field's Lipschitz constant (the reference's, raised by the edits of the fast pipeline).
  double lipschitz() const { return lipschitz_; }
  // Counts mirror() calls that changed a value (a query's kept results are stale after one).
  std::uint64_t generation() const { return generation_; }
  std::size_t brick_count() const { return bricks_.size() / kSamples; }
  std::size_t spare_bricks() const { return (bricks_.capacity() - bricks_.size()) / kSamples; }

  // Copy-on-write (the edit on the worker thread, FieldEditWorker below). The servo reads the
  // published table (index_: corners(), at(), sample(), lipschitz()); the worker reads and writes
  // its own table, which names, for every brick a batch changed, a copy taken from a pool
  // reserved here (a brick is copied once per batch; the published brick is only read); a batch
  // ends with the list of its swaps (slot, copy, retired brick), which publish() writes into the
  // published table (brick pointers, no sample copied). A retired brick goes back to the pool by
  // recycle() (the worker, once the servo can no longer hold a pointer to it).
  struct Swap {
    std::size_t slot = 0;
    std::int32_t brick = 0;    // the batch's copy
    std::int32_t retired = 0;  // the brick it replaces (< 0: an all-outside or all-inside slot)
  };
  // Setup only (allocates): `pool` bricks for the copies (with the spare room of the
  // constructor); the copy then takes its bricks from the pool only (no read-through slot).
  void enable_copy_on_write(std::size_t pool);
  bool copy_on_write() const { return cow_; }
  // The worker's side (COW only, one thread; no allocation, no throw): the stored value of s in
  // the worker's table; whether every brick holding s is a copy of this batch (taking the copies
  // from the pool; false: the pool is empty, nothing written); after SampledField::raise of s,
  // its value into those copies (worker_prepare first); the Lipschitz update on the worker's
  // table; the batch's swaps; the end of a batch (its copies become ordinary bricks of the
  // worker's table); a retired brick back to the pool.
  float worker_at(int sx, int sy, int sz) const;
  bool worker_prepare(int sx, int sy, int sz);
  void worker_mirror(int sx, int sy, int sz);
  void worker_include_cells(const int lo[3], const int hi[3]);
  double worker_lipschitz() const { return worker_lipschitz_; }
  std::span<const Swap> worker_swaps() const { return swaps_; }
  void worker_end_batch();
  void recycle(std::int32_t brick) { free_.push_back(brick); }  // within the pool's capacity
  std::size_t pool_free() const { return free_.size(); }
  // The servo's side: the batch's swaps into the published table and its Lipschitz constant.
  void publish(std::span<const Swap> swaps, double lipschitz);

 private:
  // The worst squared cell slope over the cells include_cells measures, on `table`.
  double worst_cells(const std::int32_t* table, const int lo[3], const int hi[3]) const;
  // The stored value of sample s on `table`.
  float value_on(const std::int32_t* table, int sx, int sy, int sz) const;
  // The 8 corners of cell s on `table` (no kept brick).
  void corners_on(const std::int32_t* table, const int s[3], float c[8]) const;
  // The bricks holding sample s (up to 8: its own and those whose apron holds it), as slots and
  // local offsets; returns how many.
  int holders(int sx, int sy, int sz, std::size_t sl[8], int local[8]) const;

  std::size_t slot(int bx, int by, int bz) const {
    return static_cast<std::size_t>(bx) +
           static_cast<std::size_t>(nb_) *
               (static_cast<std::size_t>(by) + static_cast<std::size_t>(nb_) * bz);
  }

  const SampledField& field_;
  int m_ = 0, nb_ = 0;
  float out_ = 0.0f, in_ = 0.0f;
  double h_ = 0.0;
  double lipschitz_ = 1.0;
  std::uint64_t generation_ = 0;
  std::vector<std::int32_t> index_;
  std::vector<float> bricks_;  // brick id * 729 + x + 9 (y + 9 z)
  // The last brick read (temporal coherence): its slot and first sample.
  mutable std::size_t last_slot_ = std::numeric_limits<std::size_t>::max();
  mutable const float* last_brick_ = nullptr;
  // Copy-on-write (above): the worker's table, its Lipschitz constant, which bricks are copies of
  // the current batch, the batch's swaps, and the pool's free bricks.
  bool cow_ = false;
  std::vector<std::int32_t> worker_index_;
  double worker_lipschitz_ = 1.0;
  std::vector<std::uint8_t> fresh_;
  std::vector<Swap> swaps_;
  std::vector<std::int32_t> free_;
};

// The twin of dentsim::FieldSolid on FieldBricks (header comment). `tooth` and `bricks` must
// outlive it.
class FieldSolid {
 public:
  FieldSolid(const VoxelTooth& tooth, const FieldBricks& bricks) : tooth_(tooth), bricks_(bricks) {}
  // The proxy core's field-only paths, as dentsim::FieldSolid (its twin: the same steps).
  static constexpr bool kFieldPaths = true;

  const VoxelTooth& tooth() const { return tooth_; }
  SignedDistance distance(const Vec3& x, double reach) const;
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const;
  double lipschitz() const { return bricks_.lipschitz(); }
  // dentsim::FieldSolid::slope from the kept query (the push-out asks it right after distance(x)
  // and normal(x) at the same x).
  double slope(const Vec3& x) const;
  // dentsim::FieldSolid::sweep_advance on the kept query's cell (the sweep asks it right after
  // distance(y) at the same y: no second gather).
  double sweep_advance(const Vec3& y, const SignedDistance& sd, const Vec3& dir, double clearance,
                       double slack, double left) const;
  // distance() calls, those answered by the free-space certificate, and queries that read the
  // field (counters for tests and benchmarks).
  long distances() const { return distances_; }
  long certified() const { return certified_; }
  long evaluated() const { return evaluated_; }

 private:
  struct Query {
    Vec3 x = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
    std::uint64_t generation = 0;
    bool deep = false;
    double value = 0.0;
    Vec3 gradient = Vec3::Zero();
    // The cell the query read: its corners, x's cell coordinates, and whether x lies in the
    // lattice (no coordinate clamped).
    float corners[8] = {};
    double t[3] = {};
    bool in_lattice = false;
  };
  // The field at x: deep-inside test, phi and gradient (the reference's arithmetic), kept.
  const Query& query(const Vec3& x) const;

  const VoxelTooth& tooth_;
  const FieldBricks& bricks_;
  mutable Query last_;
  mutable bool have_exact_ = false;  // x0_, phi0_: the last exact query (certificate)
  mutable Vec3 x0_ = Vec3::Zero();
  mutable double phi0_ = 0.0;
  mutable long distances_ = 0, certified_ = 0, evaluated_ = 0;
};

// The exact voxel distances the field edit asked before, kept for the next edits (temporal
// coherence: consecutive edits are of neighbouring voxels and scan mostly the same samples).
// Claim: a sample s outside the solid (its voxel empty) whose query d = sd(tooth, p(s), reach)
// found nearest voxel v (found), or found nothing within reach (not found), gets the same double
// from the same query later while v is still solid (found), or forever (not found), as long as
// the tooth only loses voxels (drilling). Proof: outside, the query (reference/tooth/sdf.cc
// outside_distance, and its twin fast::signed_distance) returns sqrt(best2), best2 the minimum of
// box_distance2(s, voxel) over the solid voxels with box_distance2 < reach^2 (each the same double
// for the same voxel and point), or reach when there is none. Removing voxels shrinks that set;
// s's voxel stays empty (the same branch); a minimum over a subset that still holds the argmin v
// is the same double; an empty set stays empty. The edit asks with a reach that may be shorter
// than c_out (reference/tooth/field_edit_core.h): then a listed solid voxel lies within it, so the
// query finds the least distance (found), and any later query of s (whose reach is again at least
// a solid voxel's distance, or c_out) has that minimum too while v is solid; "not found" is kept
// only from a query at c_out. The edit no longer queries inside samples (a closed form); keep()
// still refuses them. Direct-mapped, fixed size: nothing allocates in the tick.
class VoxelDistanceCache {
 public:
  VoxelDistanceCache() : entries_(kEntries) {}
  // phi of the query at sample `key` (its flat index) if kept and still valid (header comment).
  bool lookup(const VoxelTooth& tooth, std::uint64_t key, double* phi) const;
  // Keeps the query at sample `key` at point x when x is outside the solid.
  void keep(const VoxelTooth& tooth, std::uint64_t key, const Vec3& x, const SignedDistance& sd);
  long hits() const { return hits_; }
  long misses() const { return misses_; }

 private:
  static constexpr std::size_t kEntries = 8192;
  struct Entry {
    std::uint64_t key = 0;  // sample index + 1 (0: empty)
    double phi = 0.0;
    std::size_t voxel = 0;
    bool found = false;
  };
  std::vector<Entry> entries_;
  mutable long hits_ = 0, misses_ = 0;
};

// The twin of dentsim::edit_field_for_removed_voxels: the same samples scanned, queried (with
// `sd`, or answered by `cache` when it holds the same double; FieldEditStats::samples_queried
// counts both, as the reference's rule asks), raised (on `field`, then mirrored into `bricks`),
// the same stats; the Lipschitz constant raised in `bricks` (header comment). `bricks` must
// mirror `field`; `cache` may be null. `cursor` and `budget` as the reference's (a budgeted edit).
bool edit_field_for_removed_voxels(SampledField* field, FieldBricks* bricks,
                                   const VoxelTooth& tooth, std::span<const std::size_t> removed,
                                   SignedDistanceFn sd, FieldEditStats* stats,
                                   VoxelDistanceCache* cache = nullptr,
                                   FieldEditCursor* cursor = nullptr, long budget = 0);

// The drilling and the field edit at a fixed latency L on a worker thread (the reference's
// specification: dentsim::ToothContactProvider::set_field_edit_latency;
// docs/derivations/field_contact.md §8). The servo hands each tick's cut over (next_batch and
// submit, from drill(): g, the contact, T); the worker, started here, takes the batches in order
// and on its own copy of the tooth (the grid as the earlier batches left it) collects the cut set
// (SurfaceCutSet, the reference's collect_cut_set where it cannot answer), does the work and the
// removal (dentsim::drill_tick on its own drill state: the grid, right after that tick's
// drilling), subtracts the removed voxels from `field` and from the bricks' copies (FieldBricks
// copy-on-write: the servo keeps reading the published bricks), and marks the batch done.
// publish(t), at the start of tick t's contacts(), swaps in the bricks of every batch of tick
// <= t - L and hands each batch's drilling (Cut: the removed voxels, the drill state's counts,
// the 8^3 bricks of the worker's tooth the removal changed) to the servo's sink, which copies
// those bricks into the servo's tooth (its grid, octree, codes and surface bits: the state the
// same removal voxel by voxel leaves, without re-deriving it; ToothBricks, fast/tooth/cut_set.h)
// and logs the tick. A removal that changed more bricks than a batch holds (kReplayBricks) is
// replayed voxel by voxel (SurfaceVoxels::remove; counted: replay_shortfalls).
// In simulation a due batch that is not done is the servo's to finish:
// if the worker has not started it, the servo does it itself (the same edit on the same state,
// so the run is the reference's, bitwise, and repeatable; counted as a takeover, at most one a
// publish), else it waits for the worker to finish it (the rest of one batch). In real time it
// publishes a batch at the first tick it is done and counts the late ones. Retired bricks return
// to the pool at the publish after the one that retired them.
// Handoff: single producer (the servo), a ring of L + 64 batches and four counters (submitted,
// claimed, done, published; release/acquire). Exactly one thread edits each batch: it claims
// batch k by moving `claimed` from k to k + 1 (compare-and-swap) while done == k, so the batches'
// edits run one at a time, in order, each on the state the last one left (the tooth's copy, the
// field, the bricks' pool and table, the kept distances), whichever thread did it; the worker
// that loses a claim waits for done to pass k. The waits are futex waits on 32-bit atomics
// (std::atomic<int>::wait: no mutex). The worker with nothing to do watches the signal for a spin
// window (`spin`, yielding its core every 50 us) before it parks, and submit() wakes it only when
// it is parked (a flag both sides access sequentially consistently, so no wake is lost): while
// the servo drills, its next cut comes within a tick and the servo never pays a wake. Nothing on the servo's side allocates, throws or locks
// (a takeover included); the worker neither allocates nor throws. The thread is joined by the
// destructor.
class FieldEditWorker {
 public:
  // What the drilling of a tick, done by the worker, left (the servo's sink reads it at publish).
  struct Cut {
    FieldDrillCut cut;                 // as handed over
    bool collected = false;            // the cut set was not empty (the tick is logged)
    std::uint8_t material = kEmpty;    // the heaviest share's
    std::vector<std::size_t> removed;  // in removal order (drill_tick's)
    ToothBricks bricks;                // the worker's tooth's bricks the removal changed
    // The drill state's figures right after the removal (the work table stays the worker's).
    std::array<std::int64_t, kMaterialCount> removed_voxels{};
    bool pulp_exposed = false, work_table_full = false;
    double delivered_j = 0.0, carry_j = 0.0;
  };
  // The servo's side of publish(): room() whether it can take one more batch's removed voxels
  // this tick, done() each published batch's drilling, in tick order. Neither may allocate or
  // throw.
  class Sink {
   public:
    virtual bool room() const = 0;
    virtual void done(const Cut& cut) = 0;

   protected:
    ~Sink() = default;
  };

  // `field` and `bricks` (copy-on-write enabled here) must outlive it; `tooth` (the grid before
  // the first cut) and `state` (its drill state) are copied. `batch_capacity`: the most voxels a
  // batch's edit takes. `tip`, `params`: the drilling's.
  // `spin`: how long the worker watches for the next cut before it parks (0: it parks at once).
  // The default covers a 1 kHz servo's tick with room: a drilling servo never wakes the worker.
  static constexpr std::chrono::nanoseconds kDefaultSpin = std::chrono::milliseconds(2);
  FieldEditWorker(SampledField* field, FieldBricks* bricks, const VoxelTooth& tooth, int latency,
                  bool real_time, std::size_t batch_capacity, const ToolTip& tip,
                  const DrillParams& params, const DrillState& state,
                  std::chrono::nanoseconds spin = kDefaultSpin);
  ~FieldEditWorker();
  FieldEditWorker(const FieldEditWorker&) = delete;
  FieldEditWorker& operator=(const FieldEditWorker&) = delete;

  // Servo: hands tick cut.tick's cut over, its edit taking at most `limit` of the removed voxels
  // (the rest: shortfalls). False when every slot of the ring holds an unpublished batch (a late
  // real-time worker: not cut).
  bool submit(const FieldDrillCut& cut, std::size_t limit);
  // Simulation: what publish did in the worker's stead (in real time it never does either).
  struct StandIn {
    long takeovers = 0;  // batches the servo edited itself (the worker had not started them)
    long waits = 0;      // batches the servo waited for (the worker was editing them)
    // The wall time of both [ns]: steady_clock read before and after each takeover and each wait
    // (on those two paths only: no clock is read in real time or when the batch is done).
    long ns = 0;
  };
  // Servo, at the start of tick `tick`: publishes the due batches while sink.room(), each to
  // sink.done(); adds their edit stats to `stats`, their incomplete edits to `*shortfalls`, the
  // late publishes to `*late` (real time), the batches the servo edited itself or waited for,
  // and the time it took, to `*stand_in` (simulation).
  void publish(long tick, Sink& sink, FieldEditStats* stats, long* shortfalls, long* late,
               StandIn* stand_in);
  int latency() const { return latency_; }
  bool real_time() const { return real_time_; }
  const VoxelDistanceCache& distance_cache() const { return cache_; }
  // Setup (a real-time loop): the worker thread at SCHED_FIFO `priority` (just below its
  // servo's). Returns "" when granted, else why not (the thread keeps its policy).
  std::string set_fifo_priority(int priority);
  // The batches the worker thread edited (the rest of the published ones the servo did); read
  // them with every batch published.
  int worker_batches() const { return worker_batches_.load(std::memory_order_acquire); }
  // Servo: the submits that found the worker parked and woke it (the rest found it editing or
  // spinning). Thread scheduling decides it: a figure, not a result.
  long wakes() const { return wakes_; }
  // Whether the worker has parked (tests: a submit now wakes it).
  bool parked() const { return parked_.load(std::memory_order_seq_cst); }
  // Tests: while held, the worker claims no batch (the servo does each when it is due);
  // wait_until_done() blocks until every submitted batch is done (not while held).
  void hold(bool held);
  void wait_until_done() const;

 private:
  struct Batch {
    Cut cut;
    std::size_t limit = 0;
    long dropped = 0;                  // removed voxels beyond the limit (not edited)
    std::vector<std::size_t> voxels;  // the edit's: the removed voxels sorted by box
    std::vector<FieldBricks::Swap> swaps;
    FieldEditStats stats;  // the edit's counts for this batch
    double lipschitz = 1.0;
    bool complete = true;
  };
  void run();  // the worker thread
  // The worker: true as soon as the signal moves from `seen` within the spin window, false when
  // the window passes first.
  bool spin_until_signalled(int seen) const;
  // Batch `number`'s drilling and edit, by whichever thread claimed it (the state it edits is one
  // batch's at a time: the claims are in order, each after the last batch is done).
  void edit(Batch& b, int number);
  // The drilling of b's cut on tooth_ (into b.cut and b.voxels).
  void drill(Batch& b);

  std::chrono::nanoseconds spin_;
  SampledField* field_;
  FieldBricks* bricks_;
  VoxelTooth tooth_;  // the worker's: the grid after the batches drilled so far
  SurfaceCutSet cut_set_;  // on tooth_
  ToolTip tip_;
  DrillParams params_;
  DrillState drill_state_;  // the worker's (its work table)
  std::vector<std::size_t> candidates_;  // collect_cut_set's, where cut_set_ cannot answer
  std::vector<Contact> shares_;
  std::vector<std::size_t> share_voxels_;
  std::vector<std::uint8_t> brick_marks_;  // ToothBricks::take's, one per brick slot
  VoxelDistanceCache cache_;
  FieldEditStats worker_stats_;  // the edit's running counts
  int latency_;
  bool real_time_;
  std::vector<Batch> ring_;
  // Retired bricks waiting for the publish after the one that retired them: (brick, batch).
  std::vector<std::pair<std::int32_t, int>> retired_;
  std::size_t retired_head_ = 0;
  int submitted_here_ = 0, published_here_ = 0;  // the servo's copies of the counters
  std::atomic<int> submitted_{0}, claimed_{0}, done_{0}, published_{0};
  std::atomic<int> signal_{0};  // bumped by submit(), hold() and the destructor (wakes the worker)
  std::atomic<int> worker_batches_{0};
  std::atomic<bool> stop_{false}, held_{false};
  std::atomic<bool> parked_{false};  // the worker is (about to be) asleep on signal_
  long wakes_ = 0;                   // the servo's
  std::thread thread_;
};

// The fast pipeline's provider of the field model: dentsim::ToothContactProvider with the field
// steps replaced by their twins and the cut set by CutSetProvider's (fast/tooth/cut_set.h;
// everything else, the contact, the drilled voxels, the edit queue, is the reference's code). With setup.field_edit_latency > 0 and drilling, the edit runs
// on a FieldEditWorker at that latency (bitwise the reference provider with
// set_field_edit_latency(L)); 0: the reference's budget path on the servo thread. Throws what
// the reference provider throws.
class FieldContactProvider final : public CutSetProvider, private FieldEditWorker::Sink {
 public:
  FieldContactProvider(VoxelTooth& tooth, const PipelineToothSetup& setup);
  ~FieldContactProvider() override;
  const FieldBricks& bricks() const { return bricks_; }
  const FieldSolid& solid() const { return solid_; }
  // The edit's kept voxel distances (the worker's when there is one: read them only with every
  // batch published, e.g. after L ticks without drilling).
  const VoxelDistanceCache& distance_cache() const {
    return worker_ != nullptr ? worker_->distance_cache() : cache_;
  }
  double field_value(const Vec3& x) const override;
  std::string set_worker_priority(int priority) override;
  // Published removals replayed voxel by voxel: more changed bricks than a batch holds (tests).
  long replay_shortfalls() const { return replay_shortfalls_; }
  // The worker's thread, if any (tests).
  const FieldEditWorker* worker() const { return worker_.get(); }
  FieldEditWorker* worker() { return worker_.get(); }

 protected:
  const Vec3& update_field_proxy(SurfaceProxy* proxy, const Vec3& c) override;
  bool edit_field(SampledField* field, std::span<const std::size_t> removed,
                  FieldEditStats* stats, FieldEditCursor* cursor, long budget) override;
  void prepare_field_latency(int ticks) override;
  void hand_off_field_cut(const FieldDrillCut& cut) override;
  void publish_field_edits(long tick) override;

 private:
  // FieldEditWorker::Sink: the worker's drilling of a published batch on the servo's grid.
  bool room() const override;
  void done(const FieldEditWorker::Cut& cut) override;

  VoxelTooth& tooth_;
  SampledField* field_;
  bool real_time_;
  FieldBricks bricks_;
  FieldSolid solid_;
  VoxelDistanceCache cache_;
  FieldEditWorker::StandIn stand_in_;  // publish's (the base's takeover, wait and ns counts)
  long replay_shortfalls_ = 0;
  std::unique_ptr<FieldEditWorker> worker_;  // last: joined before the bricks go
};

// The fast pipeline's tooth for the field model (fast::make_fast_tooth). Throws InputError
// without setup.field.
std::unique_ptr<PipelineTooth> make_fast_field_tooth(VoxelTooth& tooth,
                                                     const PipelineToothSetup& setup);

}  // namespace dentsim::fast
