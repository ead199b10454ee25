// Tests are being written.
#include <gtest/gtest.h>
