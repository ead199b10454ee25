#pragma once
/// \file
/// chasles-bench sections on a server under hostile or careless load (issue 14).

namespace chasles {

/// A 1 s rrt_connect plan's latency alone, behind two `long_budget` rrt_star plans of another
/// client on 2 workers (default --long-share), and behind them with --long-share 1 (no cap).
void BenchFairness(int repeats, double long_budget);

/// RSS of a server process after `uploads` distinct 50 MB STL uploads into a 256 MiB cache,
/// after a large-reply plan, and after the request that took 4.4 GB before caps.
void BenchMemory(int uploads);

}  // namespace chasles
