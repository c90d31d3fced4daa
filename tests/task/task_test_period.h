// The control period of the task tests' fake devices and planners.
#pragma once

namespace vlab::task {

inline constexpr double kPeriod = 0.002;  // s: 500 Hz, the PA10 scenes' control period

}  // namespace vlab::task
