// The dense work of one supernode in a supernodal triangular solve with L (forward) and
// L' (backward), on its rows gathered into w. The supernode is m rows by at least k
// columns, column-major with leading dimension m (CHOLMOD's layout), its first rows its
// own columns; only the first k columns are solved (a split factor stops at the
// separator, split_cholesky.h). T is float for preconditioner copies, double for direct
// solves; w is double either way.
#pragma once

namespace uvpress::solve {

// In: w[0, k) the right-hand side, w[k, m) zero. Out: w[0, k) solved, w[k, m) the updates
// to add to those rows (minus L(k:m, 0:k) times the solution).
template <class T>
inline void supernode_forward(const T* L, int m, int k, double* w) {
  for (int j = 0; j < k; ++j) {
    const T* col = L + long(j) * m;
    const double xj = w[j] / double(col[j]);
    w[j] = xj;
    for (int i = j + 1; i < m; ++i) w[i] -= double(col[i]) * xj;
  }
}

// In: w[0, k) the right-hand side, w[k, m) the solution at those rows. Out: w[0, k) solved.
template <class T>
inline void supernode_backward(const T* L, int m, int k, double* w) {
  for (int j = k - 1; j >= 0; --j) {
    const T* col = L + long(j) * m;
    // Four partial sums in a fixed order: vectorizable, and the same bits everywhere.
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
    int i = j + 1;
    for (; i + 4 <= m; i += 4) {
      a0 += double(col[i]) * w[i];
      a1 += double(col[i + 1]) * w[i + 1];
      a2 += double(col[i + 2]) * w[i + 2];
      a3 += double(col[i + 3]) * w[i + 3];
    }
    for (; i < m; ++i) a0 += double(col[i]) * w[i];
    w[j] = (w[j] - ((a0 + a1) + (a2 + a3))) / double(col[j]);
  }
}

}  // namespace uvpress::solve
