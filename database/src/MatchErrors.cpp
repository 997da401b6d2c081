// MatchErrors.cpp — leave-one-out calibration of match errors and their prediction.
#include "brittle/database/MatchErrors.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "brittle/database/DescriptorIndex.h"
#include "brittle/database/FragmentDatabase.h"

namespace brittle {

namespace {

// The q-quantile of sorted values, by linear interpolation between order statistics.
double quantileOfSorted(const std::vector<double>& sorted, double q) {
  const double at = q * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<size_t>(std::floor(at));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (at - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

}  // namespace

double matchFrequencyError(const Eigen::VectorXd& matchedHz, const Eigen::VectorXd& truthHz) {
  if (matchedHz.size() < 3 || truthHz.size() < 3) return std::numeric_limits<double>::quiet_NaN();
  return ((matchedHz.head<3>() - truthHz.head<3>()).array().abs() / truthHz.head<3>().array().abs()).maxCoeff();
}

Result<MatchErrorModel> calibrateMatchErrors(const FragmentDatabase& database, DescriptorKind kind,
                                             const MatchErrorSettings& settings) {
  const DescriptorMatrix& rows = database.descriptorsOf(kind);
  const auto count = static_cast<int64_t>(database.entries.size());
  if (settings.bins < 1) return invalidArgument("match errors: bins must be >= 1");
  if (!database.hasPhysics()) return invalidArgument("match errors: the database has no physics");
  if (rows.cols() == 0) return invalidArgument(std::string("match errors: no ") + descriptorKindName(kind) + " descriptors");
  if (count < 2) return invalidArgument("match errors: need at least two entries");
  auto index = DescriptorIndex::build(rows.data(), rows.rows(), rows.cols(), database.indexSettings[static_cast<size_t>(kind)]);
  if (!index) return index.error();

  std::vector<std::pair<double, double>> pairs;  // (distance, error)
  int64_t ids[2];
  float squared[2];
  for (int64_t i = 0; i < count; ++i) {
    const Eigen::VectorXd& own = database.entries[static_cast<size_t>(i)].asset.modal.frequenciesHz;
    if (own.size() < 3) continue;  // before the search: an entry without three modes is no query
    if (Status st = index.value().query(rows.data() + i * rows.cols(), 2, ids, squared); !st) return st.error();
    // The nearest other entry: a duplicate of entry i may come first, so take whichever is not i.
    const int slot = ids[0] == i ? 1 : 0;
    const double error = matchFrequencyError(database.entries[static_cast<size_t>(ids[slot])].asset.modal.frequenciesHz, own);
    if (std::isnan(error)) continue;
    pairs.emplace_back(std::sqrt(static_cast<double>(std::max(squared[slot], 0.0f))), error);
  }
  if (pairs.size() < 2) return invalidArgument("match errors: fewer than two entries with three modes");
  return fitMatchErrors(std::move(pairs), settings);
}

Result<MatchErrorModel> fitMatchErrors(std::vector<std::pair<double, double>> pairs, const MatchErrorSettings& settings) {
  if (settings.bins < 1) return invalidArgument("match errors: bins must be >= 1");
  if (pairs.empty()) return invalidArgument("match errors: no samples");
  for (const auto& [distance, error] : pairs) {
    if (!(std::isfinite(distance) && distance >= 0.0 && std::isfinite(error) && error >= 0.0))
      return invalidArgument("match errors: a sample's distance or error is negative or not finite");
  }
  std::sort(pairs.begin(), pairs.end());
  MatchErrorModel model;
  model.samples = static_cast<int64_t>(pairs.size());
  const auto bins = static_cast<size_t>(std::clamp<int64_t>(model.samples / 4, 1, settings.bins));
  double runningMedian = 0.0, runningP90 = 0.0;
  for (size_t b = 0; b < bins; ++b) {
    const size_t begin = b * pairs.size() / bins, end = (b + 1) * pairs.size() / bins;
    std::vector<double> errors;
    for (size_t i = begin; i < end; ++i) errors.push_back(pairs[i].second);
    std::sort(errors.begin(), errors.end());
    runningMedian = std::max(runningMedian, quantileOfSorted(errors, 0.5));
    runningP90 = std::max({runningP90, runningMedian, quantileOfSorted(errors, 0.9)});
    model.distance.push_back(pairs[end - 1].first);
    model.medianError.push_back(runningMedian);
    model.p90Error.push_back(runningP90);
  }
  return model;
}

Status calibrateDatabaseMatchErrors(FragmentDatabase& database, const MatchErrorSettings& settings) {
  const bool calibrate = database.entries.size() >= 2 && database.hasPhysics();
  for (DescriptorKind kind : kAllDescriptorKinds) {
    MatchErrorModel& model = database.matchErrors[static_cast<size_t>(kind)];
    model = MatchErrorModel{};
    if (!calibrate || database.descriptorsOf(kind).cols() == 0) continue;
    auto made = calibrateMatchErrors(database, kind, settings);
    if (!made) return Error{made.error().code, std::string(descriptorKindName(kind)) + " " + made.error().message};
    model = std::move(made).value();
  }
  return Ok{};
}

MatchErrorPrediction predictMatchError(const MatchErrorModel& model, double distance) {
  MatchErrorPrediction p;
  if (model.empty() || !std::isfinite(distance)) return p;
  auto bin = std::lower_bound(model.distance.begin(), model.distance.end(), distance);
  p.beyondRange = bin == model.distance.end();
  const auto i = static_cast<size_t>(p.beyondRange ? model.distance.size() - 1 : bin - model.distance.begin());
  p.median = model.medianError[i];
  p.p90 = model.p90Error[i];
  return p;
}

Status validateMatchErrorModel(const MatchErrorModel& m) {
  const size_t n = m.distance.size();
  if (m.medianError.size() != n || m.p90Error.size() != n) return invalidArgument("match errors: lengths differ");
  if (n > 1024) return invalidArgument("match errors: more than 1024 bins");
  if (n > 0 && m.samples < static_cast<int64_t>(n)) return invalidArgument("match errors: fewer samples than bins");
  for (size_t i = 0; i < n; ++i) {
    const bool finite = std::isfinite(m.distance[i]) && std::isfinite(m.medianError[i]) && std::isfinite(m.p90Error[i]);
    if (!finite || m.distance[i] < 0.0 || m.medianError[i] < 0.0 || m.p90Error[i] < m.medianError[i])
      return invalidArgument("match errors: bin " + std::to_string(i) + " is not finite, negative or has p90 < median");
    if (i > 0 && (m.distance[i] < m.distance[i - 1] || m.medianError[i] < m.medianError[i - 1] ||
                  m.p90Error[i] < m.p90Error[i - 1]))
      return invalidArgument("match errors: bin " + std::to_string(i) + " decreases");
  }
  return Ok{};
}

}  // namespace brittle
