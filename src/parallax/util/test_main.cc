#include <gtest/gtest.h>

#include "parallax/math/random.h"

// Every test binary seeds the shared generator so that runs are repeatable.
int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  parallax::SetPRNGSeed(0);
  return RUN_ALL_TESTS();
}
