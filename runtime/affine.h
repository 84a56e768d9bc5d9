// Column-major 4x4 affine matrix product shared by the runtime's jobs (internal: not part of the API).
#pragma once

namespace rigbake::runtime::detail {

// out = a * b for column-major 4x4 affine matrices (the last row of both is 0 0 0 1).
template <typename Real>
inline void multiplyAffine(const Real* a, const Real* b, Real* out) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 3; ++r) {
      out[c * 4 + r] = a[r] * b[c * 4] + a[4 + r] * b[c * 4 + 1] + a[8 + r] * b[c * 4 + 2] + (c == 3 ? a[12 + r] : Real(0));
    }
    out[c * 4 + 3] = c == 3 ? Real(1) : Real(0);
  }
}

}  // namespace rigbake::runtime::detail
