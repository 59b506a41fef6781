// The exploration's tours: how long a trip through every frontier goal is from each of them, so
// that the explorer can choose the goal that begins the shortest trip (finish one side of the
// house before crossing to the other) instead of the nearest one.
#pragma once

#include <vector>

namespace mbot {
namespace core {

/// For each goal i of the n x n matrix `d` of distances between goals (row-major, symmetric, any
/// unit, all >= 0), the length of the shortest open path that starts at i and visits every other
/// goal once (ending anywhere). Exact for n <= exact_max, 16 at most (dynamic programming over
/// subsets: a 2^n x n table, n^2 2^n steps, 0.6 M and 1.4 ms at 12). Beyond it, from each start a
/// nearest-neighbour path shortened by 2-opt (reversing a stretch) and segment moves (a stretch
/// put elsewhere, either way round) until neither shortens it: an upper bound (on random floors of
/// 11 goals the shortest from 86% of the starts, at most 14% longer; 0.4 ms at 20 goals, 5 ms at
/// 40). Throws std::invalid_argument when d is not n x n or holds a negative or non-finite distance.
std::vector<double> shortestPathsThroughAll(const std::vector<double>& d, int n, int exact_max = 12);

}  // namespace core
}  // namespace mbot
