// Decimation of long runs for figures: a few thousand points per curve, extrema kept.
#pragma once

#include <cstddef>
#include <vector>

#include "fivebar/io/output.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// Rows a figure can show: with more than `2 * buckets` rows, the rows are split into
/// `buckets` consecutive groups and each keeps its first row and the rows where one of the
/// plotted quantities (theta, omega, alpha, M1, M2, N, Mf, P_diss, E_diss and the `extra`
/// columns) reaches its minimum or maximum over the group. Returns indices, increasing.
std::vector<size_t> decimation_indices(const std::vector<sim::Row>& rows,
                                       const std::vector<Column>& extra, size_t buckets);

/// Rows and extra columns at `indices`.
void select_rows(const std::vector<sim::Row>& rows, const std::vector<Column>& extra,
                 const std::vector<size_t>& indices, std::vector<sim::Row>* rows_out,
                 std::vector<Column>* extra_out);

}  // namespace fivebar::io
