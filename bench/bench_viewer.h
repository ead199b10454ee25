#pragma once
/// \file
/// `chasles-bench --section viewer` (issue 19): how long the viewer page takes to load in headless
/// Chromium (the page's own load_ms: from navigation start to the first frame drawn with every
/// robot and plot ready) for a Panda trajectory of ~10 s sampled at 1 kHz, beside the same page
/// of a 1 s trajectory at 10 ms; and the page's size and the time to write it.

#include <string>

namespace chasles {

struct ViewerBenchOptions {
  std::string examples_dir;
  std::string chromium = "chromium-headless-shell";
  int runs = 5;
};

/// Prints a markdown table to stdout.
void BenchViewer(const ViewerBenchOptions& options);

}  // namespace chasles
