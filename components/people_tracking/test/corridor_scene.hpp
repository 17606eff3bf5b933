// A corridor for the tests (test_detector, test_bench): walls 1.05 m to either side of the x axis from x_from to
// x_to, a door opening 1 m wide every 6 m with its door leaf open 0.9 m into the room, and the rooms' back walls
// 6 m out -- the geometry where a wall's first returns after an opening are seen at a grazing angle
// (docs/benchmarks.md "Corridor walls").
#pragma once

#include "cairn/people_tracking/scene.hpp"

namespace cairn::people_tracking::test_scenes {

inline void addCorridorWithDoors(Scene& s, double x_from, double x_to) {
  for (double side : {-1.0, 1.0}) {
    for (double x = x_from; x < x_to; x += 6.0) {
      s.addSegment({x, 1.05 * side}, {x + 5.0, 1.05 * side}, ObjectClass::kWall);
      s.addSegment({x + 5.0, 1.05 * side}, {x + 5.0, 1.95 * side}, ObjectClass::kDoor);
    }
    s.addSegment({x_from, 6.0 * side}, {x_to, 6.0 * side}, ObjectClass::kWall);  // rooms' back walls
  }
}

}  // namespace cairn::people_tracking::test_scenes
