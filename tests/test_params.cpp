#include <gtest/gtest.h>
#include "core/params.hpp"
TEST(Params, Placeholder) { EXPECT_TRUE(true); }
