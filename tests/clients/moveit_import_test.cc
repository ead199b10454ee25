#include <gtest/gtest.h>

TEST(MoveItImport, Placeholder) { SUCCEED(); }
