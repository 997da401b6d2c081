// MatchErrorsTest.cpp — the leave-one-out calibration of match errors (MatchErrors.h) on a
// designed database whose answers are known, the prediction, and the model in a pack.
#include "brittle/database/MatchErrors.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>

#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/Pack.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// Twenty pairs of entries. Pair j sits at 100 j on the first moment axis, its two entries
// d_j = 0.1 (j + 1) apart; entry 2j rings at 100 Hz, entry 2j + 1 at 100 (1 + e_j) Hz with
// e_j = 0.01 (j + 1). Leave one out, each entry's nearest other entry is its partner: entry 2j
// measures e_j, entry 2j + 1 measures e_j / (1 + e_j), both at distance d_j.
FragmentDatabase pairedDatabase() {
  FragmentDatabase db;
  db.referenceMaterial = testing::makeGlassMaterial("reference");
  const int pairs = 20;
  DescriptorMatrix& moments = db.descriptors[static_cast<size_t>(DescriptorKind::Moment)];
  moments = DescriptorMatrix::Zero(2 * pairs, 2);
  db.indexSettings[static_cast<size_t>(DescriptorKind::Moment)].kind = DescriptorIndexSettings::Kind::BruteForce;
  for (int i = 0; i < 2 * pairs; ++i) {
    const int j = i / 2;
    moments(i, 0) = static_cast<float>(100.0 * j + (i % 2 == 1 ? 0.1 * (j + 1) : 0.0));
    FragmentEntry e;
    e.asset.name = "entry-" + std::to_string(i);
    e.asset.materialName = db.referenceMaterial.name;
    e.asset.tetMesh.nodes = Eigen::MatrixX3d::Identity(4, 3);
    e.asset.tetMesh.tets.resize(1, 4);
    e.asset.tetMesh.tets << 0, 1, 2, 3;
    const double f = i % 2 == 1 ? 100.0 * (1.0 + 0.01 * (j + 1)) : 100.0;
    e.asset.modal.frequenciesHz = Eigen::Vector3d::Constant(f);
    e.asset.modal.eigenvaluesRad2PerS2 = (2.0 * M_PI * e.asset.modal.frequenciesHz).array().square();
    db.entries.push_back(std::move(e));
  }
  return db;
}

TEST(MatchErrors, LeaveOneOutOnPairsGivesTheDesignedErrorsPerBin) {
  const FragmentDatabase db = pairedDatabase();
  auto model = calibrateMatchErrors(db, DescriptorKind::Moment);
  ASSERT_TRUE(model) << model.error().message;
  const MatchErrorModel& m = model.value();
  EXPECT_EQ(m.samples, 40);
  ASSERT_EQ(m.distance.size(), 8u);  // 40 samples, 5 a bin
  // Bin 0 holds pairs 0 and 1 and the smaller error of pair 2 (d = 0.3): its errors sorted are
  // e0/(1+e0), e0, e1/(1+e1), e1, e2/(1+e2), so the median is 0.02 / 1.02.
  EXPECT_NEAR(m.distance[0], 0.3, 1e-4);  // float descriptors
  EXPECT_NEAR(m.medianError[0], 0.02 / 1.02, 1e-12);
  // The last bin holds pairs 16 (its larger error), 17, 18 and 19: 90th percentile between e19/(1+e19) and e19.
  EXPECT_NEAR(m.distance.back(), 2.0, 1e-4);
  EXPECT_GT(m.p90Error.back(), 0.2 / 1.2);
  EXPECT_LE(m.p90Error.back(), 0.2);
  for (size_t b = 1; b < m.distance.size(); ++b) {
    EXPECT_GT(m.distance[b], m.distance[b - 1]);
    EXPECT_GE(m.medianError[b], m.medianError[b - 1]);
    EXPECT_GE(m.p90Error[b], m.medianError[b]);
  }
  EXPECT_TRUE(validateMatchErrorModel(m));

  // A distance falls in the first bin whose upper distance reaches it; beyond the last, the last.
  const MatchErrorPrediction near = predictMatchError(m, 0.05);
  EXPECT_EQ(near.median, m.medianError[0]);
  EXPECT_FALSE(near.beyondRange);
  EXPECT_EQ(predictMatchError(m, m.distance[0]).p90, m.p90Error[0]);
  EXPECT_EQ(predictMatchError(m, m.distance[0] + 0.01).p90, m.p90Error[1]);
  const MatchErrorPrediction far = predictMatchError(m, 50.0);
  EXPECT_TRUE(far.beyondRange);
  EXPECT_EQ(far.p90, m.p90Error.back());
  EXPECT_TRUE(std::isnan(predictMatchError(MatchErrorModel{}, 0.1).median));
}

// A scene's own (distance, error) pairs: 12 samples make 3 bins of 4, in distance order.
TEST(MatchErrors, FitsAScenesOwnSamples) {
  std::vector<std::pair<double, double>> samples;
  for (int i = 11; i >= 0; --i) samples.emplace_back(0.1 * i, 0.01 * (i % 4) + 0.1 * (i / 4));
  auto model = fitMatchErrors(samples);
  ASSERT_TRUE(model) << model.error().message;
  ASSERT_EQ(model.value().distance.size(), 3u);
  EXPECT_EQ(model.value().samples, 12);
  EXPECT_DOUBLE_EQ(model.value().distance[1], 0.7);
  EXPECT_DOUBLE_EQ(model.value().medianError[1], 0.115);  // bin 1's errors 0.10, 0.11, 0.12, 0.13
  EXPECT_TRUE(validateMatchErrorModel(model.value()));
  samples.emplace_back(-0.1, 0.2);
  EXPECT_EQ(fitMatchErrors(samples).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(fitMatchErrors({}).error().code, ErrorCode::InvalidArgument);
}

TEST(MatchErrors, TheMatcherPredictsFromTheDatabasesModel) {
  FragmentDatabase db = pairedDatabase();
  ASSERT_TRUE(calibrateDatabaseMatchErrors(db));
  EXPECT_FALSE(db.matchErrors[static_cast<size_t>(DescriptorKind::Moment)].empty());
  EXPECT_TRUE(db.matchErrors[static_cast<size_t>(DescriptorKind::Voxel)].empty());  // no voxel descriptors here
  FragmentMatcherSettings ms;
  ms.enabled = {true, false, false};
  auto matcher = FragmentMatcher::build(db, ms);
  ASSERT_TRUE(matcher) << matcher.error().message;
  CanonicalFrames frames;
  frames.candidates.resize(1);
  DescriptorMatrix query(1, 2);
  query << 1900.0f - 1.5f, 0.0f;  // 1.5 from entry 38: the bin of distances up to 2
  auto m = matcher.value().matchDescriptors(frames, query, DescriptorKind::Moment, 1);
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m.value().front().entry, 38);
  const MatchErrorPrediction expected = predictMatchError(db.matchErrors[0], 1.5);
  EXPECT_EQ(m.value().front().predictedError.p90, expected.p90);
  EXPECT_EQ(m.value().front().predictedError.median, expected.median);
}

TEST(MatchErrors, RefusesWhatItCannotCalibrateAndBadModels) {
  FragmentDatabase db = pairedDatabase();
  EXPECT_EQ(calibrateMatchErrors(db, DescriptorKind::Voxel).error().code, ErrorCode::InvalidArgument);
  MatchErrorSettings none;
  none.bins = 0;
  EXPECT_EQ(calibrateMatchErrors(db, DescriptorKind::Moment, none).error().code, ErrorCode::InvalidArgument);
  db.entries[3].asset.tetMesh.tets.resize(0, 4);  // no physics
  EXPECT_EQ(calibrateMatchErrors(db, DescriptorKind::Moment).error().code, ErrorCode::InvalidArgument);

  MatchErrorModel bad;
  bad.distance = {0.1, 0.2};
  bad.medianError = {0.1, 0.05};  // decreasing
  bad.p90Error = {0.2, 0.3};
  bad.samples = 8;
  EXPECT_FALSE(validateMatchErrorModel(bad));
  bad.medianError = {0.1, 0.1};
  EXPECT_TRUE(validateMatchErrorModel(bad));
  bad.p90Error = {0.05, 0.3};  // p90 below the median
  EXPECT_FALSE(validateMatchErrorModel(bad));
}

// The model survives a pack exactly; a damaged one is refused as corrupt, naming its group.
TEST(MatchErrors, RoundTripsThroughAPackAndADamagedOneIsRefused) {
  const std::filesystem::path dir = testing::makeTempDir("match-errors");
  // A descriptors-only database (the writer checks an entry's modal data; none is needed here)
  // carrying the paired database's model.
  Pack pack;
  FragmentDatabase& db = pack.database;
  db.referenceMaterial = testing::makeGlassMaterial("reference");
  for (int i = 0; i < 4; ++i) {
    FragmentEntry e;
    e.asset.name = "box-" + std::to_string(i);
    e.asset.materialName = db.referenceMaterial.name;
    e.surface = testing::makeBoxSurface(1.0, 1.0 + i, 1.0);
    e.asset.massProperties = computeSurfaceMassProperties(e.surface, db.referenceMaterial.densityKgPerM3);
    e.baseShape = "box";
    e.cut = "planes";
    db.entries.push_back(std::move(e));
  }
  for (DescriptorKind kind : kAllDescriptorKinds)
    db.descriptors[static_cast<size_t>(kind)] = DescriptorMatrix::Zero(4, descriptorSize(kind, db.descriptorSettings));
  db.matchErrors[0] = calibrateMatchErrors(pairedDatabase(), DescriptorKind::Moment).value();
  // The bodies' frequency-error models: a Ritz one and none for checked bodies.
  db.frequencyErrors.ritz = fitMatchErrors({{0.01, 0.05}, {0.02, 0.04}, {0.05, 0.2}, {0.1, 0.3}, {0.2, 0.9}, {0.3, 0.5}, {0.4, 1.2}, {0.5, 2.0}},
                                           MatchErrorSettings{.bins = 2})
                                .value();
  db.frequencyErrors.degree = 5;
  const Status written = writePack(pack, dir / "db.h5");
  ASSERT_TRUE(written) << written.error().message;
  auto read = readPack(dir / "db.h5");
  ASSERT_TRUE(read) << read.error().message;
  for (size_t k = 0; k < kDescriptorKindCount; ++k) {
    const MatchErrorModel& a = pack.database.matchErrors[k];
    const MatchErrorModel& b = read.value().database.matchErrors[k];
    EXPECT_EQ(a.distance, b.distance);
    EXPECT_EQ(a.medianError, b.medianError);
    EXPECT_EQ(a.p90Error, b.p90Error);
    EXPECT_EQ(a.samples, b.samples);
  }
  EXPECT_FALSE(read.value().database.matchErrors[0].empty());
  const FrequencyErrorModels& bodies = read.value().database.frequencyErrors;
  EXPECT_EQ(bodies.ritz.distance, db.frequencyErrors.ritz.distance);
  EXPECT_EQ(bodies.ritz.medianError, db.frequencyErrors.ritz.medianError);
  EXPECT_EQ(bodies.ritz.p90Error, db.frequencyErrors.ritz.p90Error);
  EXPECT_EQ(bodies.ritz.samples, 8);
  EXPECT_EQ(bodies.ritz.medianError.size(), 2u);
  EXPECT_TRUE(bodies.checked.empty());  // an empty model is not written, and reads as none
  EXPECT_EQ(bodies.degree, 5);
  // Models without the degree they were calibrated at are refused.
  Pack noDegree = pack;
  noDegree.database.frequencyErrors.degree = 0;
  EXPECT_EQ(writePack(noDegree, dir / "none.h5").error().code, ErrorCode::InvalidArgument);

  const hid_t f = H5Fopen((dir / "db.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t d = H5Dopen2(f, "/database/match_errors/moment/median_error", H5P_DEFAULT);
  ASSERT_GE(d, 0);
  std::vector<double> values(pack.database.matchErrors[0].medianError.size());
  values.front() = 5.0;  // larger than the bins after it
  ASSERT_GE(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  H5Dclose(d);
  H5Fclose(f);
  auto damaged = readPack(dir / "db.h5");
  ASSERT_FALSE(damaged);
  EXPECT_NE(damaged.error().message.find("/database/match_errors/moment"), std::string::npos) << damaged.error().message;

  // A Ritz model whose 90th percentile falls below its median is PackCorrupt too.
  ASSERT_TRUE(writePack(pack, dir / "db2.h5"));
  const hid_t f2 = H5Fopen((dir / "db2.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f2, 0);
  const hid_t d2 = H5Dopen2(f2, "/database/frequency_errors/ritz/p90_error", H5P_DEFAULT);
  ASSERT_GE(d2, 0);
  const std::vector<double> below(2, 0.0);
  ASSERT_GE(H5Dwrite(d2, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, below.data()), 0);
  H5Dclose(d2);
  H5Fclose(f2);
  auto damagedRitz = readPack(dir / "db2.h5");
  ASSERT_FALSE(damagedRitz);
  EXPECT_EQ(damagedRitz.error().code, ErrorCode::PackCorrupt);
  EXPECT_NE(damagedRitz.error().message.find("/database/frequency_errors/ritz"), std::string::npos) << damagedRitz.error().message;
}

}  // namespace
}  // namespace brittle
