// The hand's terms two entries at a time (the order and why it is bitwise:
// fast/grasp_mass_model.h).
#include "fast/grasp_mass_model.h"

#include "reference/grasp_mass_model.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dentsim::fast {

void grasp_mass_terms(const Vec6& Mt, const DeviceTerms& base, const Vec6& V1, Mat6* M_hand,
                      Vec6* CTqd_hand) {
#if defined(__SSE2__)
  const double* J = base.J_t.data();  // column-major: J(k, i) = J[6 i + k]
  // W(i, k) = J(k, i) Mt_k, stored k-major: w[6 k + i]
  alignas(16) double w[36];
  for (int k = 0; k < 6; ++k) {
    const __m128d mt = _mm_set1_pd(Mt(k));
    for (int i = 0; i < 6; i += 2) {
      _mm_store_pd(w + 6 * k + i, _mm_mul_pd(_mm_set_pd(J[6 * (i + 1) + k], J[6 * i + k]), mt));
    }
  }
  double* out = M_hand->data();
  for (int j = 0; j < 6; ++j) {
    const double* Jj = J + 6 * j;  // column j: J(k, j) = Jj[k]
    __m128d b[6];
    for (int k = 0; k < 6; ++k) b[k] = _mm_set1_pd(Jj[k]);
    for (int i = 0; i < 6; i += 2) {
      const __m128d p0 = _mm_mul_pd(_mm_load_pd(w + i), b[0]);
      const __m128d p1 = _mm_mul_pd(_mm_load_pd(w + 6 + i), b[1]);
      const __m128d p2 = _mm_mul_pd(_mm_load_pd(w + 12 + i), b[2]);
      const __m128d p3 = _mm_mul_pd(_mm_load_pd(w + 18 + i), b[3]);
      const __m128d p4 = _mm_mul_pd(_mm_load_pd(w + 24 + i), b[4]);
      const __m128d p5 = _mm_mul_pd(_mm_load_pd(w + 30 + i), b[5]);
      const __m128d even = _mm_add_pd(p0, _mm_add_pd(p2, p4));
      const __m128d odd = _mm_add_pd(p1, _mm_add_pd(p3, p5));
      _mm_storeu_pd(out + 6 * j + i, _mm_add_pd(even, odd));
    }
  }
  // C_h^T qd = dJ_t/dt^T (Mt .* V1): per entry the terms k = 0, 1 in the two lanes, then 2, 3 and
  // 4, 5, summed as (p0 + (p2 + p4)) + (p1 + (p3 + p5)).
  const Vec6 mv = Mt.cwiseProduct(V1);
  const __m128d v01 = _mm_loadu_pd(mv.data());
  const __m128d v23 = _mm_loadu_pd(mv.data() + 2);
  const __m128d v45 = _mm_loadu_pd(mv.data() + 4);
  const double* Jd = base.J_t_dot.data();
  for (int i = 0; i < 6; ++i) {
    const double* c = Jd + 6 * i;
    const __m128d s = _mm_add_pd(
        _mm_mul_pd(_mm_loadu_pd(c), v01),
        _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(c + 2), v23), _mm_mul_pd(_mm_loadu_pd(c + 4), v45)));
    (*CTqd_hand)(i) = _mm_cvtsd_f64(_mm_add_sd(s, _mm_unpackhi_pd(s, s)));
  }
#else
  dentsim::grasp_mass_terms(Mt, base, V1, M_hand, CTqd_hand);
#endif
}

}  // namespace dentsim::fast
