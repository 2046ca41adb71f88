// The fast signed distance (fast/tooth/sdf.h) against the reference's (reference/tooth/sdf.h,
// itself checked against brute force in tests/tooth/sdf_test.cc), on the procedural molar at 128^3
// and after drilling: phi, the nearest point and its voxel bitwise equal on every query (boxes
// exactly as near are decided by the same order-free rule, sdf_detail::sdf_nearer), on grid-aligned
// ties too; and the surface proxy driven by either along the same tool path stays on the same g,
// step by step. The free-space certificate (FreeSpaceCertificate): every answer bitwise the
// reference's on random query sequences and on a scripted approach, press, drill and retreat, and
// every certified query checked against brute force (no solid voxel within its reach). The local
// query (LocalVoxelDistance, on the surface bits): at 64^3-512^3 on the molar and 64^3-256^3 on a
// mesh, at points near and far, on grid planes too, before and after random removals (the bits
// kept current as drilling keeps them), every answer it gives bitwise the reference's and the
// ones it declines (near a plane) few; and the proxy on it, with the certificate, step by step on
// the reference's path while a pit is drilled under it.
#include "fast/tooth/sdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "fast/tooth/cut_set.h"
#include "reference/tooth/surface_proxy_core.h"

#include "sim/scene.h"
#include "sim/simulator.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/shared_meshes.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/voxelize.h"

namespace dentsim {
namespace {

struct Agreement {
  long queries = 0, found = 0, inside = 0, mismatches = 0;
};

// One query both ways: everything bitwise equal (phi, found, nearest, voxel).
void compare(const VoxelTooth& tooth, const Vec3& x, double reach, Agreement* a) {
  const SignedDistance r = signed_distance(tooth, x, reach);
  const SignedDistance f = fast::signed_distance(tooth, x, reach);
  ++a->queries;
  if (r.found) ++a->found;
  if (r.phi < 0.0) ++a->inside;
  if (r.phi != f.phi || r.found != f.found || r.nearest != f.nearest || r.voxel != f.voxel) {
    ++a->mismatches;
    ADD_FAILURE() << "phi " << r.phi << " vs " << f.phi << ", nearest " << r.nearest.transpose()
                  << " vs " << f.nearest.transpose() << " at " << x.transpose();
  }
}

std::unique_ptr<SceneRig> molar_rig() {
  SceneRigOptions o;
  o.pipeline = "reference";
  return build_scene_rig(load_scene("drill"), o);
}

TEST(FastSignedDistance, EqualsTheReferenceOnTheMolar) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double side = g.voxel_size * g.n, h = g.voxel_size, rho = 0.5e-3;
  std::mt19937_64 rng(20261125);
  std::uniform_real_distribution<double> u(-0.1 * side, 1.1 * side);
  const double reaches[] = {1e-4, rho + 4 * h, 2 * rho, side};
  Agreement a;
  for (int trial = 0; trial < 4000; ++trial) {
    const Vec3 x = g.origin + Vec3(u(rng), u(rng), u(rng));
    compare(tooth, x, reaches[trial % 4], &a);
  }
  // Near the surface, where the proxy lives: points a little off the occlusal anchor's column.
  std::uniform_real_distribution<double> near(-2e-3, 2e-3);
  for (int trial = 0; trial < 4000; ++trial) {
    const Vec3 x = rig->anchor + Vec3(near(rng), near(rng), near(rng));
    compare(tooth, x, reaches[trial % 4], &a);
  }
  std::printf("%ld queries, %ld found, %ld inside, %ld mismatches\n", a.queries, a.found, a.inside,
              a.mismatches);
  EXPECT_EQ(a.mismatches, 0);
  EXPECT_GT(a.found, 3000);
  EXPECT_GT(a.inside, 500);
}

// Points exactly as near to several voxels: voxel centres' columns and the midpoints between them.
TEST(FastSignedDistance, TiesAreDecidedAlike) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double h = g.voxel_size;
  Agreement a;
  for (int i = -20; i <= 20; ++i) {
    for (int k = -5; k <= 25; ++k) {
      // On voxel corners, edges and face centres above and around the anchor.
      const Vec3 corner = g.origin + h * Vec3(std::floor((rig->anchor.x() - g.origin.x()) / h) + i,
                                              std::floor((rig->anchor.y() - g.origin.y()) / h),
                                              std::floor((rig->anchor.z() - g.origin.z()) / h) + k);
      compare(tooth, corner, 2e-3, &a);
      compare(tooth, corner + Vec3(0.5 * h, 0, 0), 2e-3, &a);
      compare(tooth, corner + Vec3(0.5 * h, 0.5 * h, 0), 2e-3, &a);
    }
  }
  EXPECT_EQ(a.mismatches, 0);
  EXPECT_GT(a.found, 1000);
}

// RecallingVoxelSolid answers a point asked again from what it remembers: with every reach,
// shorter or longer than the remembered one's, found or not, its answer is the reference's.
// One query of `solid` against the reference's: everything bitwise equal, counted.
void check_query(const VoxelTooth& tooth, const fast::RecallingVoxelSolid& solid, const Vec3& x,
                 double r, long* asked, long* found, long* mismatches) {
  const SignedDistance want = signed_distance(tooth, x, r);
  const SignedDistance got = solid.distance(x, r);
  ++*asked;
  if (want.found) ++*found;
  if (want.phi != got.phi || want.found != got.found || want.nearest != got.nearest ||
      want.voxel != got.voxel) {
    ++*mismatches;
    ADD_FAILURE() << "phi " << want.phi << " vs " << got.phi << " at " << x.transpose()
                  << " reach " << r;
  }
}

TEST(FastSignedDistance, RememberedAnswersAreTheQuerysOwn) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const double h = tooth.grid().voxel_size;
  std::mt19937_64 rng(20261127);
  std::uniform_real_distribution<double> near(-2e-3, 2e-3);
  std::uniform_real_distribution<double> reach(0.2 * h, 12 * h);
  long asked = 0, mismatches = 0, found = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const fast::RecallingVoxelSolid solid(tooth);
    Vec3 points[3];
    for (Vec3& p : points) p = rig->anchor + Vec3(near(rng), near(rng), near(rng));
    for (int k = 0; k < 24; ++k) {  // the same few points, every reach in turn
      const Vec3& x = points[k % 3];
      const double r = reach(rng);
      check_query(tooth, solid, x, r, &asked, &found, &mismatches);
    }
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(found, asked / 4);
  EXPECT_LT(found, asked);
}

TEST(FastSignedDistance, SurfaceProxyFollowsTheSamePathAfterDrilling) {
  auto rig = molar_rig();
  VoxelTooth& tooth = *rig->tooth;
  const double rho = 0.4e-3, h = tooth.grid().voxel_size;
  // Drill a pit into the top of the crown under the anchor, so that the path meets the cut's walls
  // and floor too.
  const VoxelGrid& g = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(g.n);
  const int ia = static_cast<int>((rig->anchor.x() - g.origin.x()) / h);
  const int ja = static_cast<int>((rig->anchor.y() - g.origin.y()) / h);
  int ka = g.n - 1;
  while (ka > 0 && !g.solid(ia, ja, ka)) --ka;
  const Vec3 top = g.center(ia, ja, ka);
  int removed = 0;
  for (int k = 0; k < tooth.grid().n; ++k) {
    for (int j = 0; j < tooth.grid().n; ++j) {
      for (int i = 0; i < tooth.grid().n; ++i) {
        const Vec3 c = tooth.grid().center(i, j, k);
        if ((c - top).norm() < 1.0e-3 && g.voxels[i + n * (j + n * k)] != 0) {
          tooth.octree.remove_voxel(i, j, k);
          ++removed;
        }
      }
    }
  }
  ASSERT_GT(removed, 100);
  SurfaceProxy ref(rho, h), fst(rho, h, &fast::signed_distance), rec(rho, h);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> step(0.0, 0.15e-3);
  Vec3 c = top + Vec3(0, 0, 2e-3);
  long steps = 0, in_contact = 0;
  for (int k = 0; k < 3000; ++k) {
    // A random walk pressed down into the tooth, with a jump now and then (a fast tool).
    c += Vec3(step(rng), step(rng), step(rng) - 0.05e-3);
    if (k % 500 == 499) c += Vec3(0, 0, -3e-3);
    if ((c - top).norm() > 4e-3) c = top + Vec3(0, 0, 1e-3);
    const Vec3 gr = ref.update(tooth, c);
    const Vec3 gf = fst.update(tooth, c);
    ASSERT_EQ(gr, gf) << "step " << k;
    // The fast pipeline's proxy update (fast::SdfContactProvider): the answers remembered.
    const Vec3 gm = rec.update_on(fast::RecallingVoxelSolid(tooth), c);
    ASSERT_EQ(gr, gm) << "step " << k;
    ++steps;
    if ((gr - c).norm() > 1e-9) ++in_contact;
  }
  std::printf("%ld steps, %ld with the proxy held outside\n", steps, in_contact);
  EXPECT_GT(in_contact, 1000);
}

// A query sequence as the proxy makes it, over many updates (a fresh RecallingVoxelSolid each, one
// certificate for all): points on a random walk about the anchor, now and then a jump, reaches
// from 0.2 h to 12 h; every answer bitwise the reference's.
TEST(FastSignedDistance, CertifiedAnswersAreTheQuerysOwn) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const double h = tooth.grid().voxel_size;
  std::mt19937_64 rng(20261127);
  std::normal_distribution<double> walk(0.0, 0.5 * h);
  std::uniform_real_distribution<double> jump(-4e-3, 4e-3);
  std::uniform_real_distribution<double> reach(0.2 * h, 12 * h);
  fast::FreeSpaceCertificate certificate;
  Vec3 x = rig->anchor + Vec3(0, 0, 3e-3);
  long asked = 0, mismatches = 0, found = 0;
  for (int update = 0; update < 3000; ++update) {
    const fast::RecallingVoxelSolid solid(tooth, &certificate);
    if (update % 200 == 199) x = rig->anchor + Vec3(jump(rng), jump(rng), jump(rng));
    for (int k = 0; k < 4; ++k) {
      x += Vec3(walk(rng), walk(rng), walk(rng));
      const double r = reach(rng);
      check_query(tooth, solid, x, r, &asked, &found, &mismatches);
    }
  }
  std::printf("%ld queries, %ld found, %ld certified, %ld searched\n", asked, found,
              certificate.certified(), certificate.evaluated());
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(found, asked / 20);
  EXPECT_GT(certificate.certified(), asked / 4);
  EXPECT_GT(certificate.evaluated(), asked / 20);
}

// The solid voxels with an empty face neighbour (or on the grid's border): the nearest point of
// the solid to a point outside it lies on one of their boxes.
std::vector<std::size_t> boundary_voxels(const VoxelGrid& g) {
  std::vector<std::size_t> out;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        if (!g.solid(i, j, k)) continue;
        if (!g.solid(i - 1, j, k) || !g.solid(i + 1, j, k) || !g.solid(i, j - 1, k) ||
            !g.solid(i, j + 1, k) || !g.solid(i, j, k - 1) || !g.solid(i, j, k + 1)) {
          out.push_back(g.index(i, j, k));
        }
      }
    }
  }
  return out;
}

// Brute force: the least distance from x to the boxes of `voxels` (exact arithmetic aside).
double brute_distance(const VoxelGrid& g, const std::vector<std::size_t>& voxels, const Vec3& x) {
  const std::size_t n = static_cast<std::size_t>(g.n);
  double best2 = std::numeric_limits<double>::infinity();
  for (const std::size_t v : voxels) {
    const int idx[3] = {static_cast<int>(v % n), static_cast<int>((v / n) % n),
                        static_cast<int>(v / (n * n))};
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double lo = g.origin[a] + g.voxel_size * idx[a];
      const double hi = g.origin[a] + g.voxel_size * (idx[a] + 1);
      const double gap = std::max({lo - x[a], 0.0, x[a] - hi});
      d2 += gap * gap;
    }
    best2 = std::min(best2, d2);
  }
  return std::sqrt(best2);
}

// The Solid the proxy runs on in the fast pipeline, checked query by query: the answer bitwise the
// reference's, and every query the certificate answers checked by brute force (the tooth's
// boundary voxels: none within its reach), so the certificate never skips a query the tip could
// reach.
class CheckedSolid {
 public:
  CheckedSolid(const VoxelTooth& tooth, fast::FreeSpaceCertificate* cert,
               const std::vector<std::size_t>* boundary, long* mismatches, long* unsafe)
      : solid_(tooth, cert), cert_(cert), boundary_(boundary), mismatches_(mismatches),
        unsafe_(unsafe) {}
  const VoxelTooth& tooth() const { return solid_.tooth(); }
  SignedDistance distance(const Vec3& x, double reach) const {
    const long before = cert_->certified();
    const SignedDistance got = solid_.distance(x, reach);
    const SignedDistance want = signed_distance(solid_.tooth(), x, reach);
    if (want.phi != got.phi || want.found != got.found || want.nearest != got.nearest ||
        want.voxel != got.voxel) {
      ++*mismatches_;
    }
    if (cert_->certified() > before) {
      const double d = brute_distance(solid_.tooth().grid(), *boundary_, x);
      if (!(d >= reach)) {
        ++*unsafe_;
        ADD_FAILURE() << "certified at " << x.transpose() << " reach " << reach
                      << ", brute-force distance " << d;
      }
    }
    return got;
  }
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const { return solid_.normal(x, sd); }
  double lipschitz() const { return 1.0; }

 private:
  fast::RecallingVoxelSolid solid_;
  fast::FreeSpaceCertificate* cert_;
  const std::vector<std::size_t>* boundary_;
  long* mismatches_;
  long* unsafe_;
};

// The top of the crown under the rig's anchor: the upper face of the highest solid voxel of its
// column.
Vec3 crown_top(const SceneRig& rig) {
  const VoxelGrid& g = rig.tooth->grid();
  const double h = g.voxel_size;
  const int ia = static_cast<int>((rig.anchor.x() - g.origin.x()) / h);
  const int ja = static_cast<int>((rig.anchor.y() - g.origin.y()) / h);
  int ka = g.n - 1;
  while (ka > 0 && !g.solid(ia, ja, ka)) --ka;
  return g.center(ia, ja, ka) + Vec3(0, 0, 0.5 * h);
}

// Appends `ticks` points on the segment from the path's last point (or `to`) to `to`.
void extend_path(std::vector<Vec3>* path, const Vec3& to, int ticks) {
  const Vec3 from = path->empty() ? to : path->back();
  for (int t = 1; t <= ticks; ++t) path->push_back(from + (to - from) * (double(t) / ticks));
}

// The contacts of the tool's sphere at tip centre c with the reference proxy's g and the fast
// one's (surface_proxy_contact, the material by either pipeline's query): the same (bitwise) or
// neither; *in_contact: whether there is one.
bool same_contact(const VoxelTooth& tooth, const Vec3& c, const ToolTip& tip, const Vec3& gr,
                  const Vec3& gf, bool* in_contact) {
  Pose pose;
  pose.x = c;
  Contact cr, cf;
  *in_contact = surface_proxy_contact(tooth, pose, tip, gr, 3000.0, 1.0, &cr);
  const bool hf =
      surface_proxy_contact(tooth, pose, tip, gf, 3000.0, 1.0, &cf, &fast::signed_distance);
  if (*in_contact != hf) return false;
  return !hf || (cr.n == cf.n && cr.x_o == cf.x_o && cr.r == cf.r && cr.depth == cf.depth &&
                 cr.material == cf.material);
}

// A scripted approach from 6 mm above the crown, a press 0.3 mm into it with a slide, a pit
// drilled under the tip (the tooth loses voxels while the certificate lives), a second press into
// the pit, and a retreat: at every tick g and the contact (reference/tooth/sdf.h
// surface_proxy_contact) bitwise the reference proxy's.
TEST(FastSignedDistance, CertificateKeepsTheContactsOnAnApproachAndRetreat) {
  auto rig = molar_rig();
  VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double rho = 0.25e-3, h = g.voxel_size;
  const std::size_t n = static_cast<std::size_t>(g.n);
  // The crown's top under the anchor.
  const Vec3 top = crown_top(*rig);
  std::vector<std::size_t> boundary = boundary_voxels(g);
  // The path: (tick, tip centre) by pieces; 0.02 mm a tick on the approach (20 mm/s at 1 kHz).
  std::vector<Vec3> path;
  auto go = [&path](const Vec3& to, int ticks) { extend_path(&path, to, ticks); };
  path.push_back(top + Vec3(0.3e-3, 0.2e-3, 6e-3));
  go(top + Vec3(0.3e-3, 0.2e-3, rho + 1e-3), 250);  // approach
  go(top + Vec3(0.0, 0.0, rho - 0.3e-3), 100);      // press
  go(top + Vec3(-0.4e-3, 0.1e-3, rho - 0.3e-3), 60);  // slide
  const std::size_t drill_at = path.size();
  go(top + Vec3(0.0, 0.0, rho - 0.8e-3), 100);       // into the pit
  go(top + Vec3(0.5e-3, -0.3e-3, rho + 5e-3), 300);  // retreat
  go(top + Vec3(1.5e-3, -0.3e-3, rho + 0.1e-3), 150);  // a second approach beside the pit
  go(top + Vec3(1.5e-3, -0.3e-3, rho + 4e-3), 100);
  SurfaceProxy ref(rho, h), fst(rho, h, &fast::signed_distance);
  fast::FreeSpaceCertificate certificate;
  const ToolTip tip{rho, Vec3::Zero()};
  long mismatches = 0, unsafe = 0, contacts = 0;
  for (std::size_t t = 0; t < path.size(); ++t) {
    if (t == drill_at) {  // a pit of radius 0.6 mm under the tip
      int removed = 0;
      for (int k = 0; k < g.n; ++k) {
        for (int j = 0; j < g.n; ++j) {
          for (int i = 0; i < g.n; ++i) {
            if ((g.center(i, j, k) - top).norm() < 0.6e-3 && g.voxels[i + n * (j + n * k)] != 0) {
              tooth.octree.remove_voxel(i, j, k);
              ++removed;
            }
          }
        }
      }
      ASSERT_GT(removed, 20);
      boundary = boundary_voxels(g);
    }
    const Vec3& c = path[t];
    const Vec3 gr = ref.update(tooth, c);
    const Vec3 gf =
        fst.update_on(CheckedSolid(tooth, &certificate, &boundary, &mismatches, &unsafe), c);
    ASSERT_EQ(gr, gf) << "tick " << t;
    bool hr = false;
    ASSERT_TRUE(same_contact(tooth, c, tip, gr, gf, &hr)) << "tick " << t;
    contacts += hr ? 1 : 0;
  }
  std::printf("%zu ticks, %ld in contact, %ld queries certified, %ld searched\n", path.size(),
              contacts, certificate.certified(), certificate.evaluated());
  EXPECT_EQ(mismatches, 0);
  EXPECT_EQ(unsafe, 0);
  EXPECT_GT(contacts, 200);
  EXPECT_GT(certificate.certified(), 1000);
}

// ---- The local query (LocalVoxelDistance) ------------------------------------------------------

// Removes voxel (i, j, k) as drill_tick does (the octree, then the local codes); true if it was
// solid.
bool remove_as_drilling(VoxelTooth* tooth, std::size_t v, std::vector<std::size_t>* removed) {
  const std::size_t n = static_cast<std::size_t>(tooth->grid().n);
  const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
  const int k = static_cast<int>(v / (n * n));
  if (tooth->octree.remove_voxel(i, j, k) == kEmpty) return false;
  reencode_local(tooth->octree.grid(), i, j, k, &tooth->codes);
  removed->push_back(v);
  return true;
}

struct LocalAgreement {
  long outside = 0, answered = 0, found = 0, mismatches = 0;
};

// One outside query by the local search against the reference's: when it answers, everything
// bitwise equal (phi, found, nearest, voxel, and the squared distance outside_distance reports).
void compare_local(const VoxelTooth& tooth, const fast::LocalVoxelDistance& local, const Vec3& x,
                   double reach, LocalAgreement* a) {
  int idx[3];
  const VoxelGrid& g = tooth.grid();
  if (sdf_detail::voxel_of(g, x, idx) && g.solid(idx[0], idx[1], idx[2])) return;  // inside
  ++a->outside;
  const SignedDistance want = signed_distance(tooth, x, reach);
  double want2;
  fast::signed_distance(tooth, x, reach, &want2);
  SignedDistance got;
  double got2 = -7.0;
  if (!local.outside(x, reach, &got, &got2)) return;
  ++a->answered;
  if (want.found) ++a->found;
  if (want.phi != got.phi || want.found != got.found || want.nearest != got.nearest ||
      want.voxel != got.voxel || want2 != got2) {
    ++a->mismatches;
    ADD_FAILURE() << "phi " << want.phi << " vs " << got.phi << ", voxel " << want.voxel << " vs "
                  << got.voxel << " at " << x.transpose() << " reach " << reach;
  }
}

// ~count queries about `tooth`: random walks of small steps from points near its surface voxels
// (the proxy's pattern: the kept voxel is the next query's first candidate), jumps, points far
// from it, some moved onto a grid plane or a few ulps from one; reaches from 0.2 h to 16 h, 2 rho
// and rho + 12 h (the certificate's widened reach).
// `surface`: the tooth's exposed voxels.
LocalAgreement random_local_queries(const VoxelTooth& tooth, const fast::LocalVoxelDistance& local,
                                    const std::vector<std::size_t>& surface, int count,
                                    unsigned seed) {
  const VoxelGrid& g = tooth.grid();
  const double h = g.voxel_size, side = h * g.n, rho = 0.5e-3;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, surface.size() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), far(-0.2 * side, 1.2 * side);
  std::uniform_real_distribution<double> dist(0.0, 3.0 * rho), reach(0.2 * h, 16.0 * h);
  std::normal_distribution<double> walk(0.0, 0.3 * h);
  const std::size_t n = static_cast<std::size_t>(g.n);
  LocalAgreement a;
  Vec3 x = Vec3::Zero();
  for (int q = 0; q < count; ++q) {
    if (q % 16 == 0) {  // a jump: near a surface voxel, or anywhere about the grid
      const std::size_t v = surface[pick(rng)];
      const Vec3 d(unit(rng), unit(rng), unit(rng));
      x = (q % 64 == 32) ? Vec3(g.origin + Vec3(far(rng), far(rng), far(rng)))
                         : Vec3(g.center(static_cast<int>(v % n), static_cast<int>((v / n) % n),
                                         static_cast<int>(v / (n * n))) +
                                dist(rng) * d.normalized());
    } else {
      x += Vec3(walk(rng), walk(rng), walk(rng));
    }
    Vec3 y = x;
    if (q % 8 == 5) {  // onto a plane origin + h i of one axis, or an ulp beside it
      const int axis = q % 3;
      const double p = g.origin[axis] + h * std::floor((y[axis] - g.origin[axis]) / h);
      y[axis] = (q / 8) % 3 == 0 ? p : std::nextafter(p, (q / 8) % 3 == 1 ? 1.0 : -1.0);
    }
    const double r = q % 5 == 0 ? 2.0 * rho : q % 5 == 1 ? rho + 12.0 * h : reach(rng);
    compare_local(tooth, local, y, r, &a);
  }
  return a;
}

// Before and after removals: `batches` of random exposed voxels removed (drill_tick's way), the
// bits updated, queries after each.
void local_query_agrees(VoxelTooth* tooth, const char* what, int count, int batches) {
  SCOPED_TRACE(what);
  fast::SurfaceVoxels surface(*tooth);
  const fast::LocalVoxelDistance local(*tooth, surface);
  LocalAgreement total;
  auto add = [&total](const LocalAgreement& a) {
    total.outside += a.outside;
    total.answered += a.answered;
    total.found += a.found;
    total.mismatches += a.mismatches;
  };
  const VoxelGrid& g = tooth->grid();
  auto exposed_voxels = [&g, tooth] {
    std::vector<std::size_t> out;
    for (std::size_t v = 0; v < g.voxels.size(); ++v) {
      if (tooth->codes.code(v) != 0) out.push_back(v);
    }
    return out;
  };
  std::vector<std::size_t> exposed = exposed_voxels();
  add(random_local_queries(*tooth, local, exposed, count, 46));
  std::mt19937_64 rng(4646);
  long removed_total = 0;
  for (int batch = 0; batch < batches; ++batch) {
    std::vector<std::size_t> removed;
    std::shuffle(exposed.begin(), exposed.end(), rng);
    // A drilled pit (a ball of 6 voxels' radius about an exposed voxel) and scattered voxels.
    const int n = g.n;
    const std::size_t c = exposed.front();
    const int ci = static_cast<int>(c % g.n), cj = static_cast<int>((c / g.n) % g.n);
    const int ck = static_cast<int>(c / (static_cast<std::size_t>(n) * n));
    for (int k = std::max(0, ck - 6); k <= std::min(n - 1, ck + 6); ++k) {
      for (int j = std::max(0, cj - 6); j <= std::min(n - 1, cj + 6); ++j) {
        for (int i = std::max(0, ci - 6); i <= std::min(n - 1, ci + 6); ++i) {
          if ((i - ci) * (i - ci) + (j - cj) * (j - cj) + (k - ck) * (k - ck) < 36) {
            remove_as_drilling(tooth, g.index(i, j, k), &removed);
          }
        }
      }
    }
    for (std::size_t r = 1; r < exposed.size() && r <= exposed.size() / 20; ++r) {
      remove_as_drilling(tooth, exposed[r], &removed);
    }
    {
      testing::AllocationScope scope;
      ASSERT_TRUE(surface.update(*tooth, removed));
      EXPECT_EQ(scope.count(), 0);
    }
    removed_total += static_cast<long>(removed.size());
    exposed = exposed_voxels();
    add(random_local_queries(*tooth, local, exposed, count, 47 + static_cast<unsigned>(batch)));
  }
  std::printf("%s: %ld outside queries, %ld answered locally (%ld found, %ld from a ball), %ld "
              "mismatches; %ld voxels removed; %ld voxels tested, %.1f a query\n",
              what, total.outside, total.answered, total.found, local.reused(), total.mismatches,
              removed_total,
              local.voxels_tested(),
              static_cast<double>(local.voxels_tested()) / static_cast<double>(local.queries()));
  EXPECT_EQ(total.mismatches, 0);
  EXPECT_EQ(local.queries(), total.outside);
  // Declined: the points put on or an ulp beside a plane (1 in 8), and only those.
  EXPECT_GT(total.answered, total.outside * 5 / 6);
  EXPECT_GT(total.found, total.answered / 3);  // signal: most queries near the surface find one
  EXPECT_LT(total.found, total.answered);
}

TEST(LocalVoxelDistance, EqualsTheReferenceOnTheMolarAt64To512BeforeAndAfterRemovals) {
  const int resolutions[] = {64, 128, 256, 512};
  for (const int n : resolutions) {
    VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, n));
    local_query_agrees(&tooth, ("molar " + std::to_string(n)).c_str(), n == 512 ? 3000 : 2500,
                       n == 512 ? 1 : 3);
  }
}

TEST(LocalVoxelDistance, EqualsTheReferenceOnAMeshAt64To256BeforeAndAfterRemovals) {
  for (const int n : {64, 128, 256}) {
    const std::unique_ptr<VoxelTooth> tooth = test::shared_molar_tooth(n);
    if (tooth == nullptr) GTEST_SKIP() << "absent: " << test::shared_data_path("molar-cc0.stl");
    local_query_agrees(tooth.get(), ("mesh " + std::to_string(n)).c_str(), 2000, 2);
  }
}

// Ties: points on voxel corners, edges and face centres above the crown (on planes of the grid:
// the local query declines them; on planes beyond the grid's top it may answer) and a hair off
// them (1e-4 h: near ties, answered).
TEST(LocalVoxelDistance, DeclinesGridPlanesAndDecidesNearTiesAlike) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double h = g.voxel_size;
  const fast::SurfaceVoxels surface(tooth);
  const fast::LocalVoxelDistance local(tooth, surface);
  LocalAgreement on, beyond, off;
  long on_from_balls = 0;
  for (int i = -20; i <= 20; ++i) {
    for (int k = -5; k <= 25; ++k) {
      const Vec3 corner = g.origin + h * Vec3(std::floor((rig->anchor.x() - g.origin.x()) / h) + i,
                                              std::floor((rig->anchor.y() - g.origin.y()) / h),
                                              std::floor((rig->anchor.z() - g.origin.z()) / h) + k);
      for (const Vec3& x : {corner, Vec3(corner + Vec3(0.5 * h, 0, 0)),
                            Vec3(corner + Vec3(0.5 * h, 0.5 * h, 0))}) {
        const Vec3 u = x - g.origin;
        const bool in_grid = u.minCoeff() >= 0.0 && u.maxCoeff() <= h * g.n;
        const long reused = local.reused();
        compare_local(tooth, local, x, 2e-3, in_grid ? &on : &beyond);
        if (in_grid) on_from_balls += local.reused() - reused;
        compare_local(tooth, local, x + Vec3(1e-4 * h, 2e-4 * h, 3e-4 * h), 2e-3, &off);
      }
    }
  }
  // On a plane only a ball (a voxel certified about an earlier point, no search) answers.
  EXPECT_EQ(on.answered, on_from_balls);
  EXPECT_EQ(on.mismatches, 0);
  EXPECT_GT(on.outside, 1000);
  EXPECT_EQ(beyond.mismatches, 0);
  EXPECT_EQ(off.mismatches, 0);
  EXPECT_EQ(off.answered, off.outside);
  EXPECT_GT(off.found, 1000);
}

// The proxy on the local query (with the certificate, as SdfContactProvider runs it): the scripted
// approach, press, slide, a pit drilled under the tip (drill_tick's way, the bits kept current),
// a press into it and a retreat; at every tick g and the contact bitwise the reference proxy's.
TEST(LocalVoxelDistance, SurfaceProxyFollowsTheReferenceWhileAPitIsDrilled) {
  auto rig = molar_rig();
  VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double rho = 0.5e-3, h = g.voxel_size;
  const Vec3 top = crown_top(*rig);
  std::vector<Vec3> path;
  auto go = [&path](const Vec3& to, int ticks) { extend_path(&path, to, ticks); };
  path.push_back(top + Vec3(0.3e-3, 0.2e-3, 6e-3));
  go(top + Vec3(0.3e-3, 0.2e-3, rho + 1e-3), 250);      // approach
  go(top + Vec3(0.0, 0.0, rho - 0.4e-3), 100);          // press
  go(top + Vec3(-0.5e-3, 0.1e-3, rho - 0.4e-3), 100);   // slide
  const std::size_t drill_from = path.size();
  go(top + Vec3(0.0, 0.0, rho - 1.2e-3), 300);          // into the pit as it is drilled
  const std::size_t drill_to = path.size();
  go(top + Vec3(0.6e-3, -0.3e-3, rho - 1.0e-3), 200);   // sideways in it
  go(top + Vec3(0.5e-3, -0.3e-3, rho + 5e-3), 300);     // retreat
  SurfaceProxy ref(rho, h), fst(rho, h, &fast::signed_distance);
  fast::SurfaceVoxels surface(tooth);
  const fast::LocalVoxelDistance local(tooth, surface);
  fast::FreeSpaceCertificate certificate;
  const ToolTip tip{rho, Vec3::Zero()};
  long contacts = 0, removed_total = 0, allocations = 0;
  std::vector<std::size_t> removed;
  removed.reserve(g.voxels.size());
  for (std::size_t t = 0; t < path.size(); ++t) {
    const Vec3& c = path[t];
    const Vec3 gr = ref.update(tooth, c);
    Vec3 gf;
    {
      testing::AllocationScope scope;
      gf = fst.update_on(fast::RecallingVoxelSolid(tooth, &certificate, &local), c);
      allocations += scope.count();
    }
    ASSERT_EQ(gr, gf) << "tick " << t;
    bool hr = false;
    ASSERT_TRUE(same_contact(tooth, c, tip, gr, gf, &hr)) << "tick " << t;
    contacts += hr ? 1 : 0;
    if (t >= drill_from && t < drill_to && hr) {
      // The voxels whose centre lies within rho + h of g (a crude bur), a tick at a time.
      removed.clear();
      const int span = static_cast<int>(rho / h) + 3;
      const int lo[3] = {static_cast<int>((gr.x() - g.origin.x()) / h) - span,
                         static_cast<int>((gr.y() - g.origin.y()) / h) - span,
                         static_cast<int>((gr.z() - g.origin.z()) / h) - span};
      for (int k = lo[2]; k <= lo[2] + 2 * span; ++k) {
        for (int j = lo[1]; j <= lo[1] + 2 * span; ++j) {
          for (int i = lo[0]; i <= lo[0] + 2 * span; ++i) {
            if (g.solid(i, j, k) && (g.center(i, j, k) - gr).norm() < rho + h) {
              remove_as_drilling(&tooth, g.index(i, j, k), &removed);
            }
          }
        }
      }
      ASSERT_TRUE(surface.update(tooth, removed));
      removed_total += static_cast<long>(removed.size());
    }
  }
  std::printf("%zu ticks, %ld in contact, %ld voxels removed; %ld certified, %ld searched, %ld "
              "local (%ld declined, %ld from a ball), %.1f voxels tested a local query\n",
              path.size(), contacts, removed_total, certificate.certified(),
              certificate.evaluated(), local.queries(), local.fallbacks(), local.reused(),
              static_cast<double>(local.voxels_tested()) / static_cast<double>(local.queries()));
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(local.reused(), local.queries() / 10);  // signal: the balls answer a share
  EXPECT_GT(contacts, 500);
  EXPECT_GT(removed_total, 100);
  EXPECT_EQ(local.queries(), certificate.evaluated());
  EXPECT_LT(local.fallbacks(), local.queries() / 100);
}

}  // namespace
}  // namespace dentsim
