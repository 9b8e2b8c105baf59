#include <gtest/gtest.h>
int dummy_fracture;
