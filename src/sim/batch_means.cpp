#include "sim/batch_means.h"

#include <algorithm>
#include <cmath>

namespace mc {

namespace {

struct Spread {
  double mean = 0, sd = 0, lag1 = 0;
};

Spread spread(const std::vector<double>& b) {
  Spread s;
  const std::size_t n = b.size();
  for (double v : b) s.mean += v / n;
  double ss = 0, cross = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ss += (b[i] - s.mean) * (b[i] - s.mean);
    if (i + 1 < n) cross += (b[i] - s.mean) * (b[i + 1] - s.mean);
  }
  s.sd = n > 1 ? std::sqrt(ss / (n - 1)) : 0;
  s.lag1 = ss > 0 ? cross / ss : 0;
  return s;
}

}  // namespace

double lag1_limit(int batches) { return std::min(0.5, 2.0 / std::sqrt(std::max(batches, 1))); }

BatchMeans batch_means(const std::vector<double>& all) {
  std::vector<double> values;
  for (double v : all)
    if (std::isfinite(v)) values.push_back(v);
  BatchMeans r;
  const int n = static_cast<int>(values.size());
  r.values = n;
  r.batches = n;
  if (n == 0) return r;
  double sum = 0;
  for (double v : values) sum += v;
  r.mean = sum / n;
  if (n < 2) return r;
  for (int m = 1;; m *= 2) {
    const int nb = n / m, skip = n - nb * m;
    std::vector<double> b(nb, 0.0);
    for (int k = 0; k < nb; ++k)
      for (int i = 0; i < m; ++i) b[k] += values[skip + k * m + i] / m;
    const Spread s = spread(b);
    r.batches = nb;
    r.batch_length = m;
    r.sem = s.sd / std::sqrt(nb);
    r.lag1 = nb >= 3 ? s.lag1 : std::numeric_limits<double>::quiet_NaN();
    if (nb < 3) {  // too few to test: trusted only if nothing was merged
      r.correlated = m > 1;
      return r;
    }
    if (!(s.lag1 > lag1_limit(nb))) {
      r.correlated = false;
      return r;
    }
    if (nb / 2 < 2) {  // correlated, and merging would leave one batch
      r.correlated = true;
      return r;
    }
  }
}

double naive_sem(const std::vector<double>& values) {
  if (values.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  return spread(values).sd / std::sqrt(static_cast<double>(values.size()));
}

bool converged(const BatchMeans& b, double tolerance) {
  return b.batches >= kMinBatches && !b.correlated && std::isfinite(b.sem) &&
         b.sem <= tolerance * std::fabs(b.mean);
}

}  // namespace mc
