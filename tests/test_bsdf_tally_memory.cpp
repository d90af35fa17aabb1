// The memory check of a BSDF request (BsdfRequest::check) counts the tallies as the run allocates
// them: the Smith walk model keeps one full tally per replicate until its error is met, and the
// turned runs of an isotropic renderer table keep the reflected total's pixel sums alone.
#include <gtest/gtest.h>

#include <string>

#include "microsim/api/bsdf_request.hpp"
#include "microsim/common.hpp"

namespace {
using namespace microsim;

BsdfRequest mirror_request(int resolution, bool models) {
  BsdfRequest r;
  r.material = "mirror";
  r.theta_i_deg = {30};
  r.phi_i_deg = {0};
  r.resolution = resolution;
  r.models = models;
  r.format = "json";
  return r;
}

// 65536 replicates of the Smith walk at resolution 1024: 65536 tallies of 2 sides x 5 slots x
// (1024^2 + 1024 + 1) pixels, bins and albedos with their second moments, about 10 TiB.
TEST(BsdfTallyMemory, TheSmithWalksReplicateTalliesAreCounted) {
  BsdfRequest r = mirror_request(1024, true);
  r.replicates = 65536;
  try {
    r.check();
    FAIL() << "a request for about 10 TiB of tallies was accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("GiB of tallies"), std::string::npos) << e.what();
  }
  // Without the model the same replicates cost nothing more: the walk sums them one at a time.
  r.models = false;
  EXPECT_NO_THROW(r.check());
}

// 41 incidences of an isotropic .bsdf at resolution 256 averaged over 16 azimuths: 41 nominal
// tallies (10 MiB each) and 41 x 15 turned runs of 1 MiB each (the reflected total's pixel sums
// and their hemisphere map), about 1 GiB in all; counted as full tallies they were 13 GiB.
TEST(BsdfTallyMemory, TheTurnedRunsOfARendererTableCountTheirPixelSumsAlone) {
  BsdfRequest r = mirror_request(256, false);
  r.format = "bsdf";
  r.theta_i_deg.clear();
  for (int t = 0; t <= 80; t += 2) r.theta_i_deg.push_back(t);
  r.table_azimuths = 16;
  EXPECT_NO_THROW(r.check());
}

}  // namespace
