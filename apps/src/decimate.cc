#include "fivebar/io/decimate.h"

#include <algorithm>

namespace fivebar::io {
namespace {

/// The plotted quantities of row i (figures 2-6).
std::vector<double> plotted(const std::vector<sim::Row>& rows, const std::vector<Column>& extra,
                            size_t i) {
  const sim::Row& r = rows[i];
  std::vector<double> v;
  v.reserve(32 + extra.size());
  for (int k = 0; k < kLinks; ++k) v.insert(v.end(), {r.theta[k], r.omega[k], r.alpha[k]});
  for (int k = 0; k < kJoints; ++k) v.insert(v.end(), {r.N[k], r.Mf[k]});
  v.insert(v.end(), {r.M1, r.M2, r.P_diss, r.E_diss});
  for (const Column& c : extra) v.push_back(c.values[i]);
  return v;
}

}  // namespace

std::vector<size_t> decimation_indices(const std::vector<sim::Row>& rows,
                                       const std::vector<Column>& extra, size_t buckets) {
  const size_t n = rows.size();
  std::vector<size_t> keep;
  if (buckets == 0 || n <= 2 * buckets) {
    for (size_t i = 0; i < n; ++i) keep.push_back(i);
    return keep;
  }
  for (size_t b = 0; b < buckets; ++b) {
    const size_t lo = b * n / buckets, hi = (b + 1) * n / buckets;
    std::vector<double> vmin = plotted(rows, extra, lo), vmax = vmin;
    std::vector<size_t> imin(vmin.size(), lo), imax(vmin.size(), lo);
    for (size_t i = lo + 1; i < hi; ++i) {
      const std::vector<double> v = plotted(rows, extra, i);
      for (size_t q = 0; q < v.size(); ++q) {
        if (v[q] < vmin[q]) vmin[q] = v[q], imin[q] = i;
        if (v[q] > vmax[q]) vmax[q] = v[q], imax[q] = i;
      }
    }
    keep.push_back(lo);
    keep.insert(keep.end(), imin.begin(), imin.end());
    keep.insert(keep.end(), imax.begin(), imax.end());
  }
  keep.push_back(n - 1);
  std::sort(keep.begin(), keep.end());
  keep.erase(std::unique(keep.begin(), keep.end()), keep.end());
  return keep;
}

void select_rows(const std::vector<sim::Row>& rows, const std::vector<Column>& extra,
                 const std::vector<size_t>& indices, std::vector<sim::Row>* rows_out,
                 std::vector<Column>* extra_out) {
  rows_out->clear();
  extra_out->clear();
  for (const Column& c : extra) extra_out->push_back({c.name, {}});
  for (size_t i : indices) {
    rows_out->push_back(rows[i]);
    for (size_t c = 0; c < extra.size(); ++c) (*extra_out)[c].values.push_back(extra[c].values[i]);
  }
}

}  // namespace fivebar::io
