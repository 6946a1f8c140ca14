// Test support for design tests: the shared paths and temporary designs.
#pragma once

#include "fabatlas/testing/paths.h"
