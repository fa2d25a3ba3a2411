#pragma once
// The bad messages of the hostile-input tests: lcmloc/hostile/messages.hpp (library
// lcmloc_hostile, shared with lcmloc-hostile-run).
#include "lcmloc/hostile/messages.hpp"
