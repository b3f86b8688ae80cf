// Correlation kernels: the products, window means and energies, box sums and
// normalisation of the cross-correlation, and the per-vector uncertainty's sums.
// Highway compiles this file once per target: foreach_target.h includes it
// again for each, with HWY_NAMESPACE naming the target; the code after
// HWY_ONCE is compiled only once and dispatches between them (the target cap
// all kernel files share is in simd_kernels.cc).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fusion/simd_correlation.cc"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
// Must follow foreach_target.h.
// clang-format off
#include "hwy/highway.h"
#include "hwy/cache_control.h"
// clang-format on

#include "fusion/simd_kernels.h"

// After foreach_target.h too, so that each target sees them.
#include <algorithm>
#include <cmath>
#include <utility>

HWY_BEFORE_NAMESPACE();
namespace bosfuse::fusion {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The lanes' sum in double: the two halves widened to double and added
// lane-wise, then reduced as a tree. Storing the lanes and adding them one
// by one (the scalar reference's column order) costs more than the
// multiply-adds themselves for a 16 px window.
template <class D>
HWY_INLINE double AddLanes(D /*d*/, hn::Vec<D> v, double total) {
#if HWY_TARGET != HWY_SCALAR  // which has one lane and no UpperHalf
  if constexpr (hn::MaxLanes(D()) >= 2) {
    const hn::Half<D> dh;
    const hn::Rebind<double, decltype(dh)> dd;
    const auto sum = hn::Add(hn::PromoteTo(dd, hn::LowerHalf(dh, v)), hn::PromoteTo(dd, hn::UpperHalf(dh, v)));
    return total + hn::GetLane(hn::SumOfLanes(dd, sum));
  }
#endif
  return total + hn::GetLane(v);
}

// Four neighbouring shifts share each load of the reference, so a multiply-
// add costs 1.25 loads rather than 2 (loads, not arithmetic, bound this
// loop), and four independent sums hide the multiply-add's latency. The
// shifts are `step` floats apart in the patch: 1 for four along a row, the
// patch's stride for four down a column.
// Columns [i, n) in vectors of d, then the rest in halves of d down to one
// lane, so no load reaches past column n of the window.
template <class D>
HWY_INLINE void FourShifts(D d, const float* HWY_RESTRICT a, const float* HWY_RESTRICT b, std::size_t stride,
                           std::size_t step, int n, int i, double* totals) {
  const int lanes = static_cast<int>(hn::Lanes(d));
  for (; i + lanes <= n; i += lanes) {
    auto s0 = hn::Zero(d), s1 = hn::Zero(d), s2 = hn::Zero(d), s3 = hn::Zero(d);
    for (int y = 0; y < n; ++y) {
      const auto va = hn::LoadU(d, a + static_cast<std::size_t>(y) * n + i);
      const float* row = b + y * stride + i;
      s0 = hn::MulAdd(va, hn::LoadU(d, row), s0);
      s1 = hn::MulAdd(va, hn::LoadU(d, row + step), s1);
      s2 = hn::MulAdd(va, hn::LoadU(d, row + 2 * step), s2);
      s3 = hn::MulAdd(va, hn::LoadU(d, row + 3 * step), s3);
    }
    totals[0] = AddLanes(d, s0, totals[0]);
    totals[1] = AddLanes(d, s1, totals[1]);
    totals[2] = AddLanes(d, s2, totals[2]);
    totals[3] = AddLanes(d, s3, totals[3]);
  }
  if constexpr (hn::MaxLanes(D()) > 1) {
    if (i < n) FourShifts(hn::Half<D>(), a, b, stride, step, n, i, totals);
  }
}

// One shift: the last of a side not a multiple of four.
template <class D>
HWY_INLINE void OneShift(D d, const float* HWY_RESTRICT a, const float* HWY_RESTRICT b, std::size_t stride, int n,
                         int i, double& total) {
  const int lanes = static_cast<int>(hn::Lanes(d));
  for (; i + lanes <= n; i += lanes) {
    auto s = hn::Zero(d);
    for (int y = 0; y < n; ++y) {
      s = hn::MulAdd(hn::LoadU(d, a + static_cast<std::size_t>(y) * n + i), hn::LoadU(d, b + y * stride + i), s);
    }
    total = AddLanes(d, s, total);
  }
  if constexpr (hn::MaxLanes(D()) > 1) {
    if (i < n) OneShift(hn::Half<D>(), a, b, stride, n, i, total);
  }
}

#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3 && !HWY_HAVE_SCALABLE
// AddLanes of eight vectors of 16 floats at once, written to out[k·stride]
// for vector k: each widened to eight doubles as AddLanes does, then the
// eight reduced together, each addition adding lanes of two vectors (one by
// one, a ±5 px search's reductions were about three quarters as many
// instructions as its multiply-adds). The lanes are paired as AddLanes
// pairs them (i with i + 4, then i + 2, then i + 1), so the sums are the
// same to the bit.
template <class D>
HWY_INLINE void AddLanesOfEight(D d, const hn::Vec<D>* v, double* HWY_RESTRICT out, std::size_t stride) {
  const hn::Half<D> dh;
  const hn::Repartition<double, D> dd;
  using VD = hn::Vec<decltype(dd)>;
  const auto widened = [&](int k) {
    return hn::Add(hn::PromoteTo(dd, hn::LowerHalf(dh, v[k])), hn::PromoteTo(dd, hn::UpperHalf(dh, v[k])));
  };
  // Lanes 0–3 of a's halves added, then lanes 0–3 of b's.
  const auto halves = [&](VD a, VD b) {
    return hn::Add(hn::ConcatLowerLower(dd, b, a), hn::ConcatUpperUpper(dd, b, a));
  };
  // Blocks 0, 2 from a's and 1, 3 from b's adjacent blocks added.
  const auto blocks = [&](VD a, VD b) {
    return hn::OddEvenBlocks(hn::Add(b, hn::SwapAdjacentBlocks(b)), hn::Add(a, hn::SwapAdjacentBlocks(a)));
  };
  // Each block: the sum of a's two lanes, then of b's.
  const auto pairs = [&](VD a, VD b) { return hn::Add(hn::InterleaveLower(dd, a, b), hn::InterleaveUpper(dd, a, b)); };
  const VD x0 = halves(widened(0), widened(1)), x1 = halves(widened(2), widened(3));
  const VD x2 = halves(widened(4), widened(5)), x3 = halves(widened(6), widened(7));
  const VD sums = pairs(blocks(x0, x1), blocks(x2, x3));
  alignas(64) double lanes[8];
  hn::Store(sums, dd, lanes);
  constexpr int kVectorOfLane[8] = {0, 4, 2, 6, 1, 5, 3, 7};
  for (int i = 0; i < 8; ++i) out[kVectorOfLane[i] * stride] = lanes[i];
}
#endif

// AccumulateProducts when a window row is one vector (n = 16 with AVX-512)
// and the whole window fits in registers beside a column of shifts' sums:
// the n reference rows are loaded once, and each patch row, loaded once per
// dx, feeds every dy whose window covers it. A multiply-add then costs 0.2
// loads rather than 1.25. Each shift's sum still runs over the window rows
// in order, as in FourShifts: the sums are the same to the bit. The loops
// are unrolled by templates so the rows and sums have fixed registers.
template <int kN, int kSide, class D>
struct ProductsInRegisters {
  using V = hn::Vec<D>;
  static constexpr int kPatchRows = kN + kSide - 1;

  // Patch row kRow's share of shift dy's sum: window row kRow − dy, if any.
  template <int kRow, int kDy>
  static HWY_INLINE void AddRow(const V* reference, V v, V* sums) {
    if constexpr (kRow - kDy >= 0 && kRow - kDy < kN) sums[kDy] = hn::MulAdd(reference[kRow - kDy], v, sums[kDy]);
  }

  template <int kRow, int... kDy>
  static HWY_INLINE void PatchRow(D d, const float* HWY_RESTRICT row, const V* reference, V* sums,
                                  std::integer_sequence<int, kDy...>) {
    const V v = hn::LoadU(d, row);
    (AddRow<kRow, kDy>(reference, v, sums), ...);
  }

  template <int... kRow>
  static HWY_INLINE void Column(D d, const float* HWY_RESTRICT patch, std::size_t stride, const V* reference, V* sums,
                                std::integer_sequence<int, kRow...>) {
    (PatchRow<kRow>(d, patch + kRow * stride, reference, sums, std::make_integer_sequence<int, kSide>()), ...);
  }

  static HWY_INLINE void Run(D d, const float* HWY_RESTRICT reference, const float* HWY_RESTRICT patch,
                             std::size_t stride, double* HWY_RESTRICT products) {
    V rows[kN];
    for (int y = 0; y < kN; ++y) rows[y] = hn::LoadU(d, reference + y * kN);
    for (int dx = 0; dx < kSide; ++dx) {
      V sums[kSide];
      for (auto& sum : sums) sum = hn::Zero(d);
      Column(d, patch + dx, stride, rows, sums, std::make_integer_sequence<int, kPatchRows>());
      int dy = 0;
      for (; dy + 8 <= kSide; dy += 8) AddLanesOfEight(d, sums + dy, products + dy * kSide + dx, kSide);
      for (; dy < kSide; ++dy) products[dy * kSide + dx] = AddLanes(d, sums[dy], 0.0);
    }
  }
};

// ProductsInRegisters for odd sides kSide … kMaxSide, where the registers
// hold them (32 with AVX-512: n rows, a column of sums and the patch row);
// false for any other shape.
template <int kSide, int kMaxSide, class D>
HWY_INLINE bool ProductsOfSide(D d, const float* reference, const float* patch, std::size_t stride, int n, int side,
                               double* products) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3 && !HWY_HAVE_SCALABLE
  constexpr int kN = static_cast<int>(hn::MaxLanes(D()));
  if constexpr (kN + kSide + 1 <= 32) {
    if (n == kN && static_cast<int>(hn::Lanes(d)) == kN && side == kSide) {
      ProductsInRegisters<kN, kSide, D>::Run(d, reference, patch, stride, products);
      return true;
    }
  }
  if constexpr (kSide + 2 <= kMaxSide)
    return ProductsOfSide<kSide + 2, kMaxSide>(d, reference, patch, stride, n, side, products);
#else
  (void)d, (void)reference, (void)patch, (void)stride, (void)n, (void)side, (void)products;
#endif
  return false;
}

// Shifts in fours along each row; the columns left over (side % 4 of them)
// in fours down the column, so that only the corner of side % 4 squared
// shifts goes one at a time (one of ±2 px's 25, not five). A lone shift's
// single sum waits on the multiply-add's latency and costs as much as four.
void AccumulateProducts(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                        double* products) {
  const hn::ScalableTag<float> d;
  if (ProductsOfSide<5, 11>(d, reference, patch, patch_stride, n, side, products)) return;
  const int row_end = side / 4 * 4;
  const auto four = [&](int dx, int dy, std::size_t step, std::size_t out_step) {
    double totals[4] = {0, 0, 0, 0};
    FourShifts(d, reference, patch + dy * patch_stride + dx, patch_stride, step, n, 0, totals);
    double* out = products + static_cast<std::size_t>(dy) * side + dx;
    for (int k = 0; k < 4; ++k) out[k * out_step] = totals[k];
  };
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < row_end; dx += 4) four(dx, dy, 1, 1);
  }
  for (int dx = row_end; dx < side; ++dx) {
    int dy = 0;
    for (; dy + 4 <= side; dy += 4) four(dx, dy, patch_stride, static_cast<std::size_t>(side));
    for (; dy < side; ++dy) {
      double total = 0;
      OneShift(d, reference, patch + dy * patch_stride + dx, patch_stride, n, 0, total);
      products[static_cast<std::size_t>(dy) * side + dx] = total;
    }
  }
}

// Σ over the window of (x − shift), or of its square, in lanes of doubles
// from widened floats, reduced once at the end; the last n % lanes columns
// of each row scalar.
template <bool kSquare>
HWY_INLINE double WindowSum(const float* HWY_RESTRICT window, std::size_t stride, int n, double shift) {
  const hn::ScalableTag<double> dd;
  const hn::Rebind<float, decltype(dd)> df;
  const int lanes = static_cast<int>(hn::Lanes(dd));
  const int vector_end = n / lanes * lanes;
  const auto vshift = hn::Set(dd, shift);
  auto acc0 = hn::Zero(dd), acc1 = hn::Zero(dd);
  double tail = 0;
  for (int y = 0; y < n; ++y) {
    const float* row = window + y * stride;
    int x = 0;
    for (; x + 2 * lanes <= vector_end; x += 2 * lanes) {
      const auto v0 = hn::Sub(hn::PromoteTo(dd, hn::LoadU(df, row + x)), vshift);
      const auto v1 = hn::Sub(hn::PromoteTo(dd, hn::LoadU(df, row + x + lanes)), vshift);
      acc0 = kSquare ? hn::MulAdd(v0, v0, acc0) : hn::Add(acc0, v0);
      acc1 = kSquare ? hn::MulAdd(v1, v1, acc1) : hn::Add(acc1, v1);
    }
    for (; x < vector_end; x += lanes) {
      const auto v = hn::Sub(hn::PromoteTo(dd, hn::LoadU(df, row + x)), vshift);
      acc0 = kSquare ? hn::MulAdd(v, v, acc0) : hn::Add(acc0, v);
    }
    for (; x < n; ++x) {
      const double v = row[x] - shift;
      tail += kSquare ? v * v : v;
    }
  }
  return hn::GetLane(hn::SumOfLanes(dd, hn::Add(acc0, acc1))) + tail;
}

void WindowMeanEnergy(const float* window, std::size_t stride, int n, double* mean, double* energy) {
  const double m = WindowSum<false>(window, stride, n, 0.0) / (double(n) * n);
  *mean = m;
  *energy = WindowSum<true>(window, stride, n, m);
}

void CentreWindow(const float* window, std::size_t stride, int n, double mean, float* out) {
  for (int y = 0; y < n; ++y) hwy::Prefetch(window + y * stride + n);  // the next node's, as in PatchBoxSums
  const hn::ScalableTag<double> dd;
  const hn::Rebind<float, decltype(dd)> df;
  const int lanes = static_cast<int>(hn::Lanes(dd));
  const auto vmean = hn::Set(dd, mean);
  for (int y = 0; y < n; ++y) {
    const float* row = window + y * stride;
    float* o = out + static_cast<std::size_t>(y) * n;
    int x = 0;
    for (; x + lanes <= n; x += lanes) {
      hn::StoreU(hn::DemoteTo(df, hn::Sub(hn::PromoteTo(dd, hn::LoadU(df, row + x)), vmean)), df, o + x);
    }
    for (; x < n; ++x) o[x] = static_cast<float>(row[x] - mean);
  }
}

// out[i] = in[i] − mean for i < count, in vectors and a scalar tail.
HWY_INLINE void SubtractRow(const float* HWY_RESTRICT in, int count, float mean, float* HWY_RESTRICT out) {
  const hn::ScalableTag<float> d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const auto vmean = hn::Set(d, mean);
  int i = 0;
  for (; i + lanes <= count; i += lanes) hn::StoreU(hn::Sub(hn::LoadU(d, in + i), vmean), d, out + i);
  for (; i < count; ++i) out[i] = in[i] - mean;
}

// Each output row from its window row found without a modulo (a division
// per row costs more than the row's subtractions); the r columns wrapped at
// either end scalar.
void CentredPeriodicTile(const float* window, std::size_t stride, int n, int radius, float mean, float* out) {
  const int p = n + 2 * radius;
  int source_row = n - radius;
  for (int y = 0; y < p; ++y, ++source_row) {
    if (source_row == n) source_row = 0;
    const float* row = window + static_cast<std::size_t>(source_row) * stride;
    float* o = out + static_cast<std::size_t>(y) * p;
    for (int x = 0; x < radius; ++x) o[x] = row[n - radius + x] - mean;
    SubtractRow(row, n, mean, o + radius);
    for (int x = 0; x < radius; ++x) o[radius + n + x] = row[x] - mean;
  }
}

// The column sums' table of a patch: row dy holds, for each of the p
// columns, the sum over patch rows dy … dy+n−1 widened to double (and the
// squares' table the sum of their squares): the first row by adding n patch
// rows to 0, each next by adding the row below it and then taking its top
// row off. Rows of p % lanes columns end scalar.
HWY_INLINE void ColumnTable(const float* HWY_RESTRICT patch, std::size_t stride, int p, int n, int side,
                            double* HWY_RESTRICT columns, double* HWY_RESTRICT column_squares) {
  const hn::ScalableTag<double> dd;
  const hn::Rebind<float, decltype(dd)> df;
  const int lanes = static_cast<int>(hn::Lanes(dd));
  std::fill(columns, columns + p, 0.0);
  std::fill(column_squares, column_squares + p, 0.0);
  for (int y = 0; y < n; ++y) {
    const float* row = patch + y * stride;
    int c = 0;
    for (; c + lanes <= p; c += lanes) {
      const auto v = hn::PromoteTo(dd, hn::LoadU(df, row + c));
      hn::StoreU(hn::Add(hn::LoadU(dd, columns + c), v), dd, columns + c);
      hn::StoreU(hn::Add(hn::LoadU(dd, column_squares + c), hn::Mul(v, v)), dd, column_squares + c);
    }
    for (; c < p; ++c) {
      const double v = row[c];
      columns[c] += v;
      column_squares[c] += v * v;
    }
  }
  for (int dy = 1; dy < side; ++dy) {
    const float* row_in = patch + (dy + n - 1) * stride;
    const float* row_out = patch + (dy - 1) * stride;
    const double* above = columns + (dy - 1) * p;
    const double* above_squares = column_squares + (dy - 1) * p;
    double* next = columns + dy * p;
    double* next_squares = column_squares + dy * p;
    int c = 0;
    for (; c + lanes <= p; c += lanes) {
      const auto in = hn::PromoteTo(dd, hn::LoadU(df, row_in + c));
      const auto out = hn::PromoteTo(dd, hn::LoadU(df, row_out + c));
      hn::StoreU(hn::Sub(hn::Add(hn::LoadU(dd, above + c), in), out), dd, next + c);
      hn::StoreU(hn::Sub(hn::Add(hn::LoadU(dd, above_squares + c), hn::Mul(in, in)), hn::Mul(out, out)), dd,
                 next_squares + c);
    }
    for (; c < p; ++c) {
      const double in = row_in[c], out = row_out[c];
      next[c] = (above[c] + in) - out;
      next_squares[c] = (above_squares[c] + in * in) - out * out;
    }
  }
}

// ColumnTable for a patch row of kVectors vectors, the last of them ending
// at column p (it overlaps the one before when p is not a multiple of the
// lanes, and computes the shared columns alike): the same operations, with
// the running sums in registers instead of a store and a reload per patch
// row. The first pass's patches, 16 px windows with ±3 to ±5 px searches,
// are 22 to 26 columns: three or four vectors with AVX-512, six or seven
// with AVX2.
template <int kVectors>
HWY_INLINE void ColumnTableInRegisters(const float* HWY_RESTRICT patch, std::size_t stride, int p, int n, int side,
                                       double* HWY_RESTRICT columns, double* HWY_RESTRICT column_squares) {
  const hn::ScalableTag<double> dd;
  const hn::Rebind<float, decltype(dd)> df;
  const int lanes = static_cast<int>(hn::Lanes(dd));
  int first_column[kVectors];
  for (int v = 0; v < kVectors; ++v) first_column[v] = std::min(v * lanes, p - lanes);
  hn::Vec<decltype(dd)> sums[kVectors], squares[kVectors];
  for (int v = 0; v < kVectors; ++v) sums[v] = squares[v] = hn::Zero(dd);
  for (int y = 0; y < n; ++y) {
    for (int v = 0; v < kVectors; ++v) {
      const auto x = hn::PromoteTo(dd, hn::LoadU(df, patch + y * stride + first_column[v]));
      sums[v] = hn::Add(sums[v], x);
      squares[v] = hn::Add(squares[v], hn::Mul(x, x));
    }
  }
  for (int dy = 0; dy < side; ++dy) {
    for (int v = 0; v < kVectors; ++v) {
      if (dy > 0) {
        const auto in = hn::PromoteTo(dd, hn::LoadU(df, patch + (dy + n - 1) * stride + first_column[v]));
        const auto out = hn::PromoteTo(dd, hn::LoadU(df, patch + (dy - 1) * stride + first_column[v]));
        sums[v] = hn::Sub(hn::Add(sums[v], in), out);
        squares[v] = hn::Sub(hn::Add(squares[v], hn::Mul(in, in)), hn::Mul(out, out));
      }
      hn::StoreU(sums[v], dd, columns + dy * p + first_column[v]);
      hn::StoreU(squares[v], dd, column_squares + dy * p + first_column[v]);
    }
  }
}

// ColumnTableInRegisters for a row of `vectors` vectors, 2 … kMaxVectors;
// false for any other count (six vectors' sums are twelve registers, which
// AVX2's sixteen hold).
template <int kMaxVectors>
HWY_INLINE bool ColumnTableOfVectors(int vectors, const float* HWY_RESTRICT patch, std::size_t stride, int p, int n,
                                     int side, double* HWY_RESTRICT columns, double* HWY_RESTRICT column_squares) {
  if (vectors == kMaxVectors) {
    ColumnTableInRegisters<kMaxVectors>(patch, stride, p, n, side, columns, column_squares);
    return true;
  }
  if constexpr (kMaxVectors > 2) {
    return ColumnTableOfVectors<kMaxVectors - 1>(vectors, patch, stride, p, n, side, columns, column_squares);
  }
  return false;
}

// Along rows of shifts first … first+kRows−1 of the table, the box: the sum
// of the first n column sums, then slid right one column per dx. Each box is
// a chain of dependent additions; the rows' chains advance together, so the
// adder has other rows' work while one waits (one row at a time, the chains'
// latency was most of the kernel's time). kRows is the exact count, so the
// running boxes stay in registers (with a count known only at run time they
// went through the stack, a store and a reload per addition).
template <int kRows>
HWY_INLINE void SlideBoxRows(const double* HWY_RESTRICT columns, const double* HWY_RESTRICT column_squares, int p,
                             int n, int side, int first, double* HWY_RESTRICT sums, double* HWY_RESTRICT squares) {
  double box[kRows], box_squares[kRows];
  for (int i = 0; i < kRows; ++i) box[i] = box_squares[i] = 0;
  for (int c = 0; c < n; ++c) {
    for (int i = 0; i < kRows; ++i) {
      box[i] += columns[(first + i) * p + c];
      box_squares[i] += column_squares[(first + i) * p + c];
    }
  }
  for (int dx = 0; dx < side; ++dx) {
    for (int i = 0; i < kRows; ++i) {
      if (dx > 0) {
        const double* row = columns + (first + i) * p;
        const double* row_squares = column_squares + (first + i) * p;
        box[i] += row[dx + n - 1] - row[dx - 1];
        box_squares[i] += row_squares[dx + n - 1] - row_squares[dx - 1];
      }
      sums[(first + i) * side + dx] = box[i];
      squares[(first + i) * side + dx] = box_squares[i];
    }
  }
}

// SlideBoxRows for `rows` rows, 1 … kMaxRows.
template <int kMaxRows>
HWY_INLINE void SlideBoxRowsOf(int rows, const double* HWY_RESTRICT columns, const double* HWY_RESTRICT column_squares,
                               int p, int n, int side, int first, double* HWY_RESTRICT sums,
                               double* HWY_RESTRICT squares) {
  if (rows == kMaxRows) {
    SlideBoxRows<kMaxRows>(columns, column_squares, p, n, side, first, sums, squares);
  } else if constexpr (kMaxRows > 1) {
    SlideBoxRowsOf<kMaxRows - 1>(rows, columns, column_squares, p, n, side, first, sums, squares);
  }
}

// The column sums' table, then the boxes along its rows in chunks of at
// most four rows, of equal size (a ±5 px search's eleven rows as 4 + 4 + 3):
// eight chains of additions keep the adders busy and fit AVX2's registers
// (all eleven in one chunk did not fit AVX-512's).
void PatchBoxSums(const float* patch, std::size_t stride, int p, int n, double* column_scratch, double* sums,
                  double* squares) {
  const int side = p - n + 1;
  // The nodes after this one along the row (nodes are evaluated in row
  // order) read the columns right of this patch: fetching the second next
  // node's now (the next one's came with the node before) hides the wait for
  // memory that otherwise opens its box sums. One node ahead hid less.
  for (int y = 0; y < p; ++y) {
    hwy::Prefetch(patch + y * stride + p + n);
    hwy::Prefetch(patch + y * stride + p + 2 * n - 1);
  }
  double* columns = column_scratch;
  double* column_squares = column_scratch + static_cast<std::size_t>(side) * p;
#if HWY_HAVE_SCALABLE  // no arrays of vectors
  const int vectors = 0;
#else
  const int lanes = static_cast<int>(hn::Lanes(hn::ScalableTag<double>()));
  const int vectors = p >= lanes ? (p + lanes - 1) / lanes : 0;
#endif
  if (!ColumnTableOfVectors<6>(vectors, patch, stride, p, n, side, columns, column_squares)) {
    ColumnTable(patch, stride, p, n, side, columns, column_squares);
  }
  constexpr int kMaxRows = 4;
  const int chunks = (side + kMaxRows - 1) / kMaxRows;
  for (int chunk = 0, first = 0; chunk < chunks; ++chunk) {
    const int rows = (side - first) / (chunks - chunk);
    SlideBoxRowsOf<kMaxRows>(rows, columns, column_squares, p, n, side, first, sums, squares);
    first += rows;
  }
}

// A vector of shifts at a time; the shifts left over (count % lanes) by the
// scalar reference, which does the same operations in the same order.
void NormaliseByEnergies(const double* products, const double* sums, const double* squares, std::size_t count,
                         double window_pixels, double reference_energy, double min_energy, double* out) {
  if (reference_energy < min_energy) {
    std::fill(out, out + count, 0.0);
    return;
  }
  const hn::ScalableTag<double> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto pixels = hn::Set(d, window_pixels), reference = hn::Set(d, reference_energy);
  const auto floor = hn::Set(d, min_energy), zero = hn::Zero(d);
  std::size_t i = 0;
  for (; i + lanes <= count; i += lanes) {
    const auto s = hn::LoadU(d, sums + i);
    const auto energy = hn::Sub(hn::LoadU(d, squares + i), hn::Div(hn::Mul(s, s), pixels));
    // Flat lanes take the root of a negative number or of ~0, then drop it.
    const auto root = hn::IfThenZeroElse(hn::Lt(energy, floor), hn::Sqrt(hn::Mul(reference, energy)));
    hn::StoreU(hn::IfThenZeroElse(hn::Eq(root, zero), hn::Div(hn::LoadU(d, products + i), root)), d, out + i);
  }
  scalar_normalise_by_energies(products + i, sums + i, squares + i, count - i, window_pixels, reference_energy,
                               min_energy, out + i);
}

// The equal-windows correlation of an n×n window pair when a window row is
// exactly one vector (n = 16 with AVX-512, 8 with AVX2): the measurement
// window is centred and each of its rows rotated by every horizontal shift
// in registers, so the periodic tile never goes through memory, and all
// (2r+1)² shifts are summed at once, each reference row loaded once per
// node. kRadius is a template argument so the sums stay in registers.
template <int kRadius, class D>
HWY_INLINE void CorrelateFullRows(D d, const float* HWY_RESTRICT reference, std::size_t reference_stride,
                                  float reference_mean, const float* HWY_RESTRICT window, std::size_t stride,
                                  double* HWY_RESTRICT products, double* mean, double* energy) {
  constexpr int kSide = 2 * kRadius + 1;
  constexpr int kMaxLanes = static_cast<int>(hn::MaxLanes(D()));
  const int n = static_cast<int>(hn::Lanes(d));
  auto total = hn::Zero(d);
  // The next node along the row (the nodes are evaluated in row order) reads
  // the columns right of these windows: fetching them now hides the wait
  // for memory that otherwise opens each window.
  for (int y = 0; y < n; ++y) {
    hwy::Prefetch(window + y * stride + n);
    hwy::Prefetch(reference + y * reference_stride + n);
  }
  for (int y = 0; y < n; ++y) total = hn::Add(total, hn::LoadU(d, window + y * stride));
  *mean = AddLanes(d, total, 0.0) / (double(n) * n);
  const auto vmean = hn::Set(d, static_cast<float>(*mean));
  // rotated[(y·kSide + dx)·n + x] = centred window (y, (x + dx − r) mod n).
  HWY_ALIGN float rotated[kMaxLanes * kSide * kMaxLanes];
  // Lane x of rotation dx takes lane (x + dx − r) mod n; n, a vector's lane
  // count, is a power of two, so the modulo is a mask, in registers.
  const hn::RebindToSigned<D> di;
  using Indices = decltype(hn::IndicesFromVec(d, hn::Zero(di)));
  Indices rotation[kSide];
  for (int dx = 0; dx < kSide; ++dx) {
    const auto lane = hn::And(hn::Iota(di, dx - kRadius + n), hn::Set(di, n - 1));
    rotation[dx] = hn::IndicesFromVec(d, lane);
  }
  auto squares = hn::Zero(d);
  for (int y = 0; y < n; ++y) {
    const auto centred = hn::Sub(hn::LoadU(d, window + y * stride), vmean);
    squares = hn::MulAdd(centred, centred, squares);
    for (int dx = 0; dx < kSide; ++dx) {
      hn::Store(hn::TableLookupLanes(centred, rotation[dx]), d, rotated + (y * kSide + dx) * n);
    }
  }
  *energy = AddLanes(d, squares, 0.0);
  hn::Vec<D> sums[kSide * kSide];
  for (auto& sum : sums) sum = hn::Zero(d);
  const auto vreference_mean = hn::Set(d, reference_mean);
  for (int y = 0; y < n; ++y) {
    const auto a = hn::Sub(hn::LoadU(d, reference + y * reference_stride), vreference_mean);
    for (int dy = 0; dy < kSide; ++dy) {
      const float* row = rotated + ((y + dy - kRadius + n) % n) * kSide * n;
      for (int dx = 0; dx < kSide; ++dx) {
        sums[dy * kSide + dx] = hn::MulAdd(a, hn::Load(d, row + dx * n), sums[dy * kSide + dx]);
      }
    }
  }
  for (int i = 0; i < kSide * kSide; ++i) products[i] = AddLanes(d, sums[i], 0.0);
}

bool EqualWindowProducts(const float* reference, std::size_t reference_stride, double reference_mean,
                         const float* window, std::size_t stride, int n, int radius, double* products, double* mean,
                         double* energy) {
  const hn::ScalableTag<float> d;
  if (static_cast<int>(hn::Lanes(d)) != n || 2 * radius >= n) return false;
  const auto a_mean = static_cast<float>(reference_mean);
  switch (radius) {
    case 1:
      CorrelateFullRows<1>(d, reference, reference_stride, a_mean, window, stride, products, mean, energy);
      return true;
    case 2:
      CorrelateFullRows<2>(d, reference, reference_stride, a_mean, window, stride, products, mean, energy);
      return true;
    default:
      return false;
  }
}
// The correlation statistics' sums: columns in chunks of eight lanes at
// most (a 16 px window's right neighbours need n − 1 ≥ lanes), the last
// chunk moved back to end at the window's last column (n − 1 for the right
// neighbours) with the lanes of columns already counted masked off, so no
// load leaves the window. Every chunk adds into the same nine vectors.
void CorrelationStatisticsSums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                               double* sums) {
  const hn::CappedTag<float, 8> d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  if (n - 1 < lanes) {
    scalar_correlation_statistics_sums(a, a_stride, b, b_stride, n, sums);
    return;
  }
  const double pixels = double(n) * n;
  const auto ma = hn::Set(d, static_cast<float>(WindowSum<false>(a, a_stride, n, 0.0) / pixels));
  const auto mb = hn::Set(d, static_cast<float>(WindowSum<false>(b, b_stride, n, 0.0) / pixels));
  const auto iota = hn::Iota(d, 0.f);
  auto c0 = hn::Zero(d), plus_x = c0, minus_x = c0, plus_y = c0, minus_y = c0, dx = c0, dx2 = c0, dy = c0, dy2 = c0;
  for (int x = 0; x < n; x += lanes) {
    const int s0 = std::min(x, n - lanes), s1 = std::min(x, n - 1 - lanes);
    const auto new0 = hn::Ge(iota, hn::Set(d, static_cast<float>(x - s0)));
    const auto new1 = hn::Ge(iota, hn::Set(d, static_cast<float>(x - s1)));
    for (int y = 0; y < n; ++y) {
      const float* ra = a + y * a_stride;
      const float* rb = b + y * b_stride;
      const auto a0 = hn::IfThenElseZero(new0, hn::Sub(hn::LoadU(d, ra + s0), ma));
      const auto b0 = hn::IfThenElseZero(new0, hn::Sub(hn::LoadU(d, rb + s0), mb));
      c0 = hn::MulAdd(a0, b0, c0);
      if (y + 1 < n) {
        const auto plus = hn::Mul(a0, hn::Sub(hn::LoadU(d, rb + b_stride + s0), mb));
        const auto minus = hn::Mul(hn::Sub(hn::LoadU(d, ra + a_stride + s0), ma), b0);
        const auto delta = hn::Sub(plus, minus);
        plus_y = hn::Add(plus_y, plus);
        minus_y = hn::Add(minus_y, minus);
        dy = hn::Add(dy, delta);
        dy2 = hn::MulAdd(delta, delta, dy2);
      }
      const auto ax = hn::IfThenElseZero(new1, hn::Sub(hn::LoadU(d, ra + s1), ma));
      const auto bx = hn::IfThenElseZero(new1, hn::Sub(hn::LoadU(d, rb + s1), mb));
      const auto plus = hn::Mul(ax, hn::Sub(hn::LoadU(d, rb + s1 + 1), mb));
      const auto minus = hn::Mul(hn::Sub(hn::LoadU(d, ra + s1 + 1), ma), bx);
      const auto delta = hn::Sub(plus, minus);
      plus_x = hn::Add(plus_x, plus);
      minus_x = hn::Add(minus_x, minus);
      dx = hn::Add(dx, delta);
      dx2 = hn::MulAdd(delta, delta, dx2);
    }
  }
  sums[kC0] = AddLanes(d, c0, 0.0);
  sums[kPlusX] = AddLanes(d, plus_x, 0.0);
  sums[kMinusX] = AddLanes(d, minus_x, 0.0);
  sums[kPlusY] = AddLanes(d, plus_y, 0.0);
  sums[kMinusY] = AddLanes(d, minus_y, 0.0);
  sums[kDeltaX] = AddLanes(d, dx, 0.0);
  sums[kDeltaX2] = AddLanes(d, dx2, 0.0);
  sums[kDeltaY] = AddLanes(d, dy, 0.0);
  sums[kDeltaY2] = AddLanes(d, dy2, 0.0);
}


// The lag products (simd_kernels.h): along y each column chunk keeps the two
// previous rows' ΔCy in registers; along x each lag l has its own chunk
// start, moved back so that the partner at c + l stays in the window, the
// lanes of columns already counted masked off.
void CorrelationLagSums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                        double* lags) {
  const hn::CappedTag<float, 8> d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  if (n - 3 - lanes < 0) {
    scalar_correlation_lag_sums(a, a_stride, b, b_stride, n, lags);
    return;
  }
  const double pixels = double(n) * n;
  lags[kMeanA] = WindowSum<false>(a, a_stride, n, 0.0) / pixels;
  lags[kMeanB] = WindowSum<false>(b, b_stride, n, 0.0) / pixels;
  const auto ma = hn::Set(d, static_cast<float>(lags[kMeanA]));
  const auto mb = hn::Set(d, static_cast<float>(lags[kMeanB]));
  const auto iota = hn::Iota(d, 0.f);
  // ΔC at columns c…c + lanes of rows y (a0, b0 there) and the next (row or column).
  const auto delta_x = [&](const float* ra, const float* rb, int c) {
    return hn::Sub(hn::Mul(hn::Sub(hn::LoadU(d, ra + c), ma), hn::Sub(hn::LoadU(d, rb + c + 1), mb)),
                   hn::Mul(hn::Sub(hn::LoadU(d, ra + c + 1), ma), hn::Sub(hn::LoadU(d, rb + c), mb)));
  };
  auto x1 = hn::Zero(d), x2 = x1, y1 = x1, y2 = x1, ends1 = x1, ends2 = x1;
  for (int x = 0; x < n; x += lanes) {
    const int s0 = std::min(x, n - lanes);
    const auto new0 = hn::Ge(iota, hn::Set(d, static_cast<float>(x - s0)));
    auto previous1 = hn::Zero(d), previous2 = previous1;
    for (int y = 0; y + 1 < n; ++y) {
      const float* ra = a + y * a_stride;
      const float* rb = b + y * b_stride;
      const auto a0 = hn::IfThenElseZero(new0, hn::Sub(hn::LoadU(d, ra + s0), ma));
      const auto b0 = hn::IfThenElseZero(new0, hn::Sub(hn::LoadU(d, rb + s0), mb));
      const auto delta = hn::Sub(hn::Mul(a0, hn::Sub(hn::LoadU(d, rb + b_stride + s0), mb)),
                                 hn::Mul(hn::Sub(hn::LoadU(d, ra + a_stride + s0), ma), b0));
      y1 = hn::MulAdd(delta, previous1, y1);
      y2 = hn::MulAdd(delta, previous2, y2);
      previous2 = previous1;
      previous1 = delta;
      if (y < 1 || y >= n - 2) ends1 = hn::Add(ends1, delta);
      if (y < 2 || y >= n - 3) ends2 = hn::Add(ends2, delta);
    }
  }
  for (int x = 0; x < n - 1; x += lanes) {
    for (int l = 1; l <= 2; ++l) {
      const int s = std::min(x, n - 1 - lanes - l);
      if (s < x && x > n - 2 - l) continue;  // no column from x on has a partner l further
      const auto fresh = hn::Ge(iota, hn::Set(d, static_cast<float>(x - s)));
      auto& sum = l == 1 ? x1 : x2;
      for (int y = 0; y < n; ++y) {
        const float* ra = a + y * a_stride;
        const float* rb = b + y * b_stride;
        sum = hn::MulAdd(hn::IfThenElseZero(fresh, delta_x(ra, rb, s)), delta_x(ra, rb, s + l), sum);
      }
    }
  }
  lags[kLagX1] = AddLanes(d, x1, 0.0);
  lags[kLagX2] = AddLanes(d, x2, 0.0);
  lags[kLagY1] = AddLanes(d, y1, 0.0);
  lags[kLagY2] = AddLanes(d, y2, 0.0);
  lags[kEndsY1] = AddLanes(d, ends1, 0.0);
  lags[kEndsY2] = AddLanes(d, ends2, 0.0);
}

}  // namespace HWY_NAMESPACE
}  // namespace bosfuse::fusion
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <array>
#include <cmath>
#include <vector>

namespace bosfuse::fusion {

HWY_EXPORT(AccumulateProducts);
HWY_EXPORT(WindowMeanEnergy);
HWY_EXPORT(CentredPeriodicTile);
HWY_EXPORT(CentreWindow);
HWY_EXPORT(EqualWindowProducts);
HWY_EXPORT(PatchBoxSums);
HWY_EXPORT(NormaliseByEnergies);
HWY_EXPORT(CorrelationStatisticsSums);
HWY_EXPORT(CorrelationLagSums);

void accumulate_products(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                         double* products) {
  HWY_DYNAMIC_DISPATCH(AccumulateProducts)(reference, patch, patch_stride, n, side, products);
}

void scalar_accumulate_products(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                                double* products) {
  std::vector<float> column(static_cast<std::size_t>(n));
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx) {
      for (int i = 0; i < n; ++i) column[i] = 0.f;
      for (int y = 0; y < n; ++y) {
        const float* a = reference + static_cast<std::size_t>(y) * n;
        const float* b = patch + (y + dy) * patch_stride + dx;
        for (int i = 0; i < n; ++i) column[i] += a[i] * b[i];
      }
      double total = 0;
      for (int i = 0; i < n; ++i) total += column[i];
      products[static_cast<std::size_t>(dy) * side + dx] = total;
    }
  }
}

void window_mean_energy(const float* window, std::size_t stride, int n, double* mean, double* energy) {
  HWY_DYNAMIC_DISPATCH(WindowMeanEnergy)(window, stride, n, mean, energy);
}

void scalar_window_mean_energy(const float* window, std::size_t stride, int n, double* mean, double* energy) {
  double sum = 0;
  for (int y = 0; y < n; ++y) {
    const float* row = window + y * stride;
    for (int x = 0; x < n; ++x) sum += row[x];
  }
  const double m = sum / (double(n) * n);
  double e = 0;
  for (int y = 0; y < n; ++y) {
    const float* row = window + y * stride;
    for (int x = 0; x < n; ++x) e += (row[x] - m) * (row[x] - m);
  }
  *mean = m;
  *energy = e;
}

void centre_window(const float* window, std::size_t stride, int n, double mean, float* out) {
  HWY_DYNAMIC_DISPATCH(CentreWindow)(window, stride, n, mean, out);
}

void scalar_centre_window(const float* window, std::size_t stride, int n, double mean, float* out) {
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) out[y * n + x] = static_cast<float>(window[y * stride + x] - mean);
  }
}

void centred_periodic_tile(const float* window, std::size_t stride, int n, int radius, float mean, float* out) {
  HWY_DYNAMIC_DISPATCH(CentredPeriodicTile)(window, stride, n, radius, mean, out);
}

void scalar_centred_periodic_tile(const float* window, std::size_t stride, int n, int radius, float mean, float* out) {
  const int p = n + 2 * radius;
  for (int y = 0; y < p; ++y) {
    for (int x = 0; x < p; ++x) {
      out[y * p + x] = window[static_cast<std::size_t>((y - radius + n) % n) * stride + (x - radius + n) % n] - mean;
    }
  }
}

bool equal_window_products(const float* reference, std::size_t reference_stride, double reference_mean,
                           const float* window, std::size_t stride, int n, int radius, double* products, double* mean,
                           double* energy) {
  return HWY_DYNAMIC_DISPATCH(EqualWindowProducts)(reference, reference_stride, reference_mean, window, stride, n,
                                                   radius, products, mean, energy);
}

void scalar_equal_window_products(const float* reference, std::size_t reference_stride, double reference_mean,
                                  const float* window, std::size_t stride, int n, int radius, double* products,
                                  double* mean, double* energy) {
  std::vector<float> centred(static_cast<std::size_t>(n) * n);
  scalar_centre_window(reference, reference_stride, n, reference_mean, centred.data());
  scalar_window_mean_energy(window, stride, n, mean, energy);
  const int p = n + 2 * radius;
  std::vector<float> tile(static_cast<std::size_t>(p) * p);
  scalar_centred_periodic_tile(window, stride, n, radius, static_cast<float>(*mean), tile.data());
  scalar_accumulate_products(centred.data(), tile.data(), static_cast<std::size_t>(p), n, 2 * radius + 1, products);
}

void patch_box_sums(const float* patch, std::size_t stride, int p, int n, double* column_scratch, double* sums,
                    double* squares) {
  HWY_DYNAMIC_DISPATCH(PatchBoxSums)(patch, stride, p, n, column_scratch, sums, squares);
}

void scalar_patch_box_sums(const float* patch, std::size_t stride, int p, int n, double* sums, double* squares) {
  const int side = p - n + 1;
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx) {
      double box = 0, box_squares = 0;
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          const double v = patch[(dy + y) * stride + dx + x];
          box += v;
          box_squares += v * v;
        }
      }
      sums[dy * side + dx] = box;
      squares[dy * side + dx] = box_squares;
    }
  }
}

void normalise_by_energies(const double* products, const double* sums, const double* squares, std::size_t count,
                           double window_pixels, double reference_energy, double min_energy, double* out) {
  HWY_DYNAMIC_DISPATCH(NormaliseByEnergies)
  (products, sums, squares, count, window_pixels, reference_energy, min_energy, out);
}

void scalar_normalise_by_energies(const double* products, const double* sums, const double* squares, std::size_t count,
                                  double window_pixels, double reference_energy, double min_energy, double* out) {
  for (std::size_t i = 0; i < count; ++i) {
    const double energy = squares[i] - sums[i] * sums[i] / window_pixels;
    const bool flat = reference_energy < min_energy || energy < min_energy;
    const double root = flat ? 0.0 : std::sqrt(reference_energy * energy);
    out[i] = root == 0.0 ? 0.0 : products[i] / root;
  }
}
void correlation_statistics_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                                 double* sums) {
  HWY_DYNAMIC_DISPATCH(CorrelationStatisticsSums)(a, a_stride, b, b_stride, n, sums);
}

void scalar_correlation_statistics_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride,
                                        int n, double* sums) {
  const auto mean_of = [n](const float* w, std::size_t stride) {
    double sum = 0;
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) sum += w[y * stride + x];
    }
    return sum / (double(n) * n);
  };
  const double mean_a = mean_of(a, a_stride), mean_b = mean_of(b, b_stride);
  const auto ca = [&](int y, int x) { return a[y * a_stride + x] - mean_a; };
  const auto cb = [&](int y, int x) { return b[y * b_stride + x] - mean_b; };
  for (int k = 0; k < kCorrelationSumCount; ++k) sums[k] = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      sums[kC0] += ca(y, x) * cb(y, x);
      if (x + 1 < n) {
        const double plus = ca(y, x) * cb(y, x + 1), minus = ca(y, x + 1) * cb(y, x);
        sums[kPlusX] += plus;
        sums[kMinusX] += minus;
        sums[kDeltaX] += plus - minus;
        sums[kDeltaX2] += (plus - minus) * (plus - minus);
      }
      if (y + 1 < n) {
        const double plus = ca(y, x) * cb(y + 1, x), minus = ca(y + 1, x) * cb(y, x);
        sums[kPlusY] += plus;
        sums[kMinusY] += minus;
        sums[kDeltaY] += plus - minus;
        sums[kDeltaY2] += (plus - minus) * (plus - minus);
      }
    }
  }
}


void correlation_lag_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                          double* lags) {
  HWY_DYNAMIC_DISPATCH(CorrelationLagSums)(a, a_stride, b, b_stride, n, lags);
}

void scalar_correlation_lag_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                                 double* lags) {
  double mean_a = 0, mean_b = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) mean_a += a[y * a_stride + x], mean_b += b[y * b_stride + x];
  }
  mean_a /= double(n) * n, mean_b /= double(n) * n;
  const auto ca = [&](int y, int x) { return a[y * a_stride + x] - mean_a; };
  const auto cb = [&](int y, int x) { return b[y * b_stride + x] - mean_b; };
  const auto dx = [&](int y, int x) { return ca(y, x) * cb(y, x + 1) - ca(y, x + 1) * cb(y, x); };
  const auto dy = [&](int y, int x) { return ca(y, x) * cb(y + 1, x) - ca(y + 1, x) * cb(y, x); };
  for (int k = 0; k < kCorrelationLagSumCount; ++k) lags[k] = 0;
  lags[kMeanA] = mean_a, lags[kMeanB] = mean_b;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x + 1 < n; ++x) {
      if (x + 2 < n) lags[kLagX1] += dx(y, x) * dx(y, x + 1);
      if (x + 3 < n) lags[kLagX2] += dx(y, x) * dx(y, x + 2);
    }
  }
  for (int y = 0; y + 1 < n; ++y) {
    for (int x = 0; x < n; ++x) {
      if (y + 2 < n) lags[kLagY1] += dy(y, x) * dy(y + 1, x);
      if (y + 3 < n) lags[kLagY2] += dy(y, x) * dy(y + 2, x);
      if (y < 1 || y >= n - 2) lags[kEndsY1] += dy(y, x);
      if (y < 2 || y >= n - 3) lags[kEndsY2] += dy(y, x);
    }
  }
}

}  // namespace bosfuse::fusion

#endif  // HWY_ONCE
