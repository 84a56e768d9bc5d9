// Which of the clips' frames the response fit solves over (pipeline/response_fit.h): spread over the
// muscles' drivers, the extremes first. Apart from the fit so that it reads on its own.
#pragma once

#include <cstddef>
#include <vector>

namespace rigbake {

// `count` of the candidate poses (their driverFeatures(), pipeline/response_fit.h) for the fit, spread over the drivers'
// range by farthest-point sampling: first the pose farthest from rest, then each time the one farthest
// from every pose taken; distances within a relative 1e-9 tie, and a tie goes to the earlier candidate
// (the same poses whatever the last bits of the features). Returned ascending (the candidates' order);
// all of them when there are no more than `count`. Even spacing in time leaves a brief extreme pose (a roll, a fall) between two
// samples; this takes the extremes first.
std::vector<size_t> chooseFitPoses(const std::vector<std::vector<double>>& features, size_t count);

}  // namespace rigbake
