// The passive decomposition's feed-forward (4.7) specialised to the structure of its matrices:
// the fast twin of decompose_locked + pd_feedforward (reference/decomposition.h), same equations
// and symbols, differing from the reference only by round-off (tests/fast/decomposition_test.cc).
//
// Structure used (every tool preset and scene has it; anything else takes the reference's path):
//   E = diag(I, Q), Q = R2^T R1:        E^T x = [x_v; Q^T x_w], E y = [y_v; Q y_w] (3x3 blocks)
//   E^T M2 E = diag(m I, Q^T J Q):      no 6x6 products with the proxy inertia M2 = diag(m I, J)
//   J = j I (isotropic, every scene's): Q^T J Q = j I and J Q W = j (Q W), no 3x3 product with J
//                                       (the reference's Q^T J Q carries round-off off j I: eps j)
//   M_d, D_d diagonal:                  M_d^-1 and D_d scale rows
// and X is never formed: with phi = M_L^-1 N (N = E^T M2 E) and X = M_L M_d^-1 B,
//   (I - phi^T) X = (M_L - N) M_L^-1 X = M1 W,   E phi^T X = E N M_L^-1 X = diag(m I, J Q) W,
//   W = M_d^-1 B,  B = [b0 BG],  b0 = F1_hat + E^T f0 - D_d (V1 - phi V1),  BG = E^T G - D_d phi E^T,
// so T1 = [M1 W0 - F1_hat, M1 WG] and T2 = diag(m I, J Q) W - F2, with phi E^T = M_L^-1 diag(m I,
// Q^T J) the one solve (six right-hand sides) and phi V1 = (phi E^T)(E V1). About 850
// multiplications against the reference's 3 100 (nine dense 6x6 products); the identities hold in
// exact arithmetic, so the two differ by round-off of the order of eps cond(M_L).
#pragma once

#include "reference/core/pipeline.h"
#include "reference/decomposition.h"

namespace dentsim::fast {

// M1 = J1^T M J1 (2.2), the device's inertia at the tool, for a symmetric M: the upper triangle
// as dot products of J1's columns with M J1's (one 6x6 product and 21 dot products instead of two
// 6x6 products), mirrored, so M1 is exactly symmetric. The reference forms (J1^T M) J1; in exact
// arithmetic the two are equal, and each computed entry is within (2 gamma_6 + gamma_6^2)
// (|J1|^T |M| |J1|)(i, j) of it (a 6-term dot product of a 6-term dot product, gamma_6 = 6 u /
// (1 - 6 u), u = 2^-53, any summation order), so the two differ entrywise by at most
// 2 (2 gamma_6 + gamma_6^2) (|J1|^T |M| |J1|)(i, j) < 25 u (|J1|^T |M| |J1|)(i, j)
// (tests/fast/decomposition_test.cc). No allocation, no throw.
void inertia_at_tool(const Mat6& J1, const Mat6& M, Mat6* M1);

// True when M_d and D_d are diagonal (the specialised path applies).
bool pd_tool_is_diagonal(const ToolDynamics& tool);

// decompose_locked (phi, M_L at the poses R1, R2 with the proxy's M2 = diag(m I, J)) and
// pd_feedforward with a diagonal M_d, D_d (pd_tool_is_diagonal(tool) must hold). false when M_L
// is not positive definite or phi is not finite (as decompose_locked). No allocation, no throw.
// What the caller knows of its inputs, each saving work on the same doubles:
//  contact_free: F2 = 0 exactly (a free tick: no contact, no anchored spring); the products with
//    F2 and its subtractions are left out (x - 0 = x, x + 0 = x: a zero's sign aside);
//  symmetric_M1: M1 exactly symmetric (inertia_at_tool's); the symmetrisation 0.5 (M1 + M1^T),
//    which is then M1 exactly, is left out.
// (tests/fast/decomposition_test.cc). T1, T2 are written only on success (untouched when false).
struct FeedforwardKnown {
  bool contact_free = false;
  bool symmetric_M1 = false;
};
bool pd_feedforward_diagonal(const Mat6& M1, const ProxyParams& proxy, const ToolDynamics& tool,
                             const Mat3& R1, const Mat3& R2, const Vec6& V1, const Vec6& F1_hat,
                             const AffineWrench& F2, AffineWrench* T1, AffineWrench* T2,
                             FeedforwardKnown known = {});
// The same with T1 kept factored, for a caller that reads T1 only at one velocity (the tick: at
// V_hat, after the solve): T1(V) = M1 W(V) - F1_hat with W(V) = W0 + WG V written to *W (W =
// M_d^-1 B above), so that T1.G = M1 WG (a 6x6 product, 216 multiplications) is never formed;
// evaluating M1 (W0 + WG V) takes 72. T2 is the same doubles as pd_feedforward_diagonal's, and so
// is W (its T1 is M1 W less [F1_hat 0], entry by entry). M1 must be exactly symmetric (the
// symmetrisation is left out: known.symmetric_M1 is taken as true). In exact arithmetic T1(V) is
// pd_feedforward_diagonal's T1.f0 + T1.G V; in floating point the two sum the same products
// m_ik w_kj v_j (and F1_hat) in another order, each within gamma_14 (|M1| (|W0| + |WG| |V|) +
// |F1_hat|) of the exact value entrywise (the deepest chain: two multiplications, 36 terms
// summed as 6 sums of 6, and the additions of W0 and F1_hat), so they differ by at most twice that,
// < 29 u (...), u = 2^-53 (tests/fast/decomposition_test.cc). No allocation, no throw.
bool pd_feedforward_diagonal_factored(const Mat6& M1, const ProxyParams& proxy,
                                      const ToolDynamics& tool, const Mat3& R1, const Mat3& R2,
                                      const Vec6& V1, const Vec6& F1_hat, const AffineWrench& F2,
                                      AffineWrench* W, AffineWrench* T2, FeedforwardKnown known = {});

// The same into a PdFeedforward.
inline bool pd_feedforward_diagonal(const Mat6& M1, const ProxyParams& proxy,
                                    const ToolDynamics& tool, const Mat3& R1, const Mat3& R2,
                                    const Vec6& V1, const Vec6& F1_hat, const AffineWrench& F2,
                                    PdFeedforward* out, FeedforwardKnown known = {}) {
  return pd_feedforward_diagonal(M1, proxy, tool, R1, R2, V1, F1_hat, F2, &out->T1, &out->T2,
                                 known);
}

}  // namespace dentsim::fast
