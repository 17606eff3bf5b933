#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "cairn/sim/rng.hpp"
#include "cairn/sim/world.hpp"

using namespace cairn::sim;

namespace {

const char* kWorld = R"(name: test
walls:
  - [[0, 0], [10, 0], [10, 5], [0, 5], [0, 0]]
segments:
  - [5, 0, 5, 2]
  - [5, 3, 5, 5, 0.9]
regions:
  - {name: left, rect: [0, 0, 5, 5]}
  - name: right
    polygon: [[5, 0], [10, 0], [10, 5], [5, 5]]
doors:
  - name: d1
    hinge: [5, 2]
    latch: [5, 3]
    schedule: [{t: 0, open: false}, {t: 10, open: true}, {t: 20, open: false}]
    period: 30
  - {name: d2, hinge: [1, 1], latch: [2, 1], open: true}
furniture:
  - name: table
    size: [1.6, 0.8]
    legs_only: true
    leg_radius: 0.03
    pose: [2, 3, 0]
  - name: box
    size: [1, 1]
    schedule: [{t: 0, pose: [7, 1, 0]}, {t: 100, pose: [8, 4, 0.5]}]
markers:
  - {name: m1, position: [9.9, 2.5]}
robot:
  start: [1, 2.5, 0]
routes:
  loop: [[1, 2.5], [8, 2.5]]
)";

std::string errorOf(const std::string& yaml) {
  try {
    parseWorld(yaml, "w.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(World, ParsesAllElements) {
  const World w = parseWorld(kWorld, "/tmp/test.yaml");
  EXPECT_EQ(w.name, "test");
  EXPECT_EQ(w.walls.size(), 4u + 2u);
  EXPECT_FLOAT_EQ(w.walls.back().reflectivity, 0.9F);
  ASSERT_EQ(w.regions.size(), 2u);
  EXPECT_EQ(w.regionAt({1, 1}), "left");
  EXPECT_EQ(w.regionAt({7, 1}), "right");
  EXPECT_EQ(w.regionAt({11, 1}), "");
  EXPECT_NEAR(w.region("left")->centroid().x, 2.5, 1e-12);
  ASSERT_EQ(w.doors.size(), 2u);
  ASSERT_EQ(w.furniture.size(), 2u);
  ASSERT_EQ(w.markers.size(), 1u);
  EXPECT_FLOAT_EQ(w.markers[0].reflectivity, 1.0F);
  EXPECT_DOUBLE_EQ(w.robot_start.x, 1.0);
  EXPECT_EQ(w.routes.at("loop").size(), 2u);
  EXPECT_DOUBLE_EQ(w.bounds_max.x, 10.0);
}

TEST(World, DoorScheduleIsPeriodic) {
  const World w = parseWorld(kWorld, "t.yaml");
  const Door& d = w.doors[0];
  EXPECT_FALSE(d.isOpen(5));
  EXPECT_TRUE(d.isOpen(10));
  EXPECT_TRUE(d.isOpen(19.9));
  EXPECT_FALSE(d.isOpen(25));
  EXPECT_TRUE(d.isOpen(45));  // 45 mod 30 = 15
  EXPECT_TRUE(w.doors[1].isOpen(1e6));
  // closed: panel hinge->latch; open: swung by +90° about the hinge
  const Segment closed = d.panel(0), open = d.panel(12);
  EXPECT_NEAR(closed.b.y, 3.0, 1e-12);
  EXPECT_NEAR(open.b.x, 4.0, 1e-12);
  EXPECT_NEAR(open.b.y, 2.0, 1e-12);
}

TEST(World, FurnitureMovesAndTableShowsOnlyLegs) {
  const World w = parseWorld(kWorld, "t.yaml");
  std::vector<Segment> segs;
  std::vector<Circle> circles;
  w.furniture[0].geometry(0, segs, circles);
  EXPECT_TRUE(segs.empty());
  ASSERT_EQ(circles.size(), 4u);
  EXPECT_NEAR(circles[0].center.x, 2 + 0.8 - 0.03, 1e-12);
  EXPECT_NEAR(circles[0].center.y, 3 + 0.4 - 0.03, 1e-12);
  EXPECT_NEAR(w.furniture[1].poseAt(50).x, 7.0, 1e-12);
  EXPECT_NEAR(w.furniture[1].poseAt(150).theta, 0.5, 1e-12);
  segs.clear();
  w.furniture[1].geometry(150, segs, circles);
  ASSERT_EQ(segs.size(), 4u);
  // the four corners lie at distance sqrt(0.5) from the centre
  for (const auto& s : segs) EXPECT_NEAR(norm(s.a - Vec2{8, 4}), std::sqrt(0.5), 1e-12);
  std::vector<Segment> dyn;
  std::vector<Circle> dync;
  w.dynamicGeometry(0, dyn, dync);
  EXPECT_EQ(dyn.size(), 2u + 4u);
  EXPECT_EQ(dync.size(), 4u + 1u);
}

TEST(World, InterpolatedFurnitureMovesContinuously) {
  const World w = parseWorld(
      "walls: [[[0,0],[10,0]]]\n"
      "furniture: [{size: [0.4, 0.4], interpolate: true, period: 40,"
      " schedule: [{t: 0, pose: [2, 1, 0]}, {t: 20, pose: [6, 1, 1]}]}]\n",
      "t.yaml");
  const Furniture& f = w.furniture[0];
  EXPECT_NEAR(f.poseAt(10).x, 4.0, 1e-12);   // half way out
  EXPECT_NEAR(f.poseAt(10).theta, 0.5, 1e-12);
  EXPECT_NEAR(f.poseAt(30).x, 4.0, 1e-12);   // half way back
  EXPECT_NEAR(f.poseAt(35).x, 3.0, 1e-12);
  EXPECT_NEAR(f.poseAt(75).x, 3.0, 1e-12);   // next period
}

TEST(WorldErrors, NameFileLineAndKey) {
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\nbogus: 1\n"), "w.yaml:3: unknown key 'bogus'");
  // a repeated key used to be accepted with its second value silently ignored
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\nwalls:\n  - [[0,0],[0,1]]\n"), "w.yaml:3: duplicate key 'walls'");
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\ndoors:\n  - {hinge: [0,0], latch: [1,0], hinge: [2,0]}\n"),
            "w.yaml:4: duplicate key 'doors[0].hinge'");
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,x]]\n"), "w.yaml:2: 'walls[0][1][1]' must be a number, got 'x'");
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\ndoors:\n  - name: d\n    latch: [1, 1]\n"),
            "w.yaml:4: missing key 'doors[0].hinge'");
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\ndoors:\n  - hinge: [0,0]\n    latch: [1,0]\n"
                    "    schedule:\n      - {t: 5, open: true}\n      - {t: 1, open: false}\n"),
            "w.yaml:8: 'doors[0].schedule[1].t' must be increasing");
  EXPECT_EQ(errorOf("name: x\n"), "w.yaml:1: world has no geometry: give 'walls', 'segments' or 'map'");
  const std::string syntax = errorOf("walls: [[0,0],\n  [1,0]\nfoo: [\n");
  EXPECT_EQ(syntax.rfind("w.yaml:", 0), 0u) << syntax;
  EXPECT_NE(syntax.find("YAML syntax"), std::string::npos) << syntax;
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\nregions:\n  - {name: a, rect: [0,0,1,1]}\n"
                    "crowd:\n  sources: [a]\n  sinks: [b]\n  base_rate: 1\n"),
            "w.yaml:7: 'crowd.sinks': unknown region 'b'");
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\nfurniture:\n  - size: [1, -1]\n    pose: [0,0,0]\n"),
            "w.yaml:4: 'furniture[0].size' must be positive");
}

TEST(WorldErrors, CrowdValuesAreRangeChecked) {
  const std::string head = "walls:\n  - [[0,0],[1,0]]\nregions:\n  - {name: a, rect: [0,0,1,1]}\n"
                           "crowd:\n  sources: [a]\n  sinks: [a]\n";
  // base_rate 1e300 passed and then hung the run (each arrival draw added nothing to the time)
  EXPECT_EQ(errorOf(head + "  base_rate: 1e300\n"), "w.yaml:8: 'crowd.base_rate' must be in [0, 3600], got 1e300");
  EXPECT_EQ(errorOf(head + "  base_rate: 3000\n  terms: [{period: 86400, amplitude: 0.5}]\n"),
            "w.yaml:9: 'crowd.terms': the peak rate base_rate × (1 + Σ|amplitude|) must be at most 3600 people per hour");
  EXPECT_EQ(errorOf(head + "  base_rate: 1\n  max_people: -1\n"),
            "w.yaml:9: 'crowd.max_people' must be an integer in [0, 1000], got -1");
  EXPECT_EQ(errorOf(head + "  base_rate: 1\n  max_people: 2.5\n"),
            "w.yaml:9: 'crowd.max_people' must be an integer in [0, 1000], got 2.5");
  EXPECT_EQ(errorOf(head + "  base_rate: 1\n  max_people: 1e300\n"),
            "w.yaml:9: 'crowd.max_people' must be an integer in [0, 1000], got 1e300");
  EXPECT_EQ(errorOf(head + "  base_rate: 1\n  speed: 5\n"), "w.yaml:9: 'crowd.speed' must be in [0.4, 2], got 5");
  EXPECT_EQ(errorOf(head + "  base_rate: 1\n  speed_sigma: -0.1\n"),
            "w.yaml:9: 'crowd.speed_sigma' must be in [0, 1], got -0.1");
  EXPECT_EQ(errorOf(head + "  base_rate: 3600\n  max_people: 1000\n"), "no error");
}

TEST(WorldErrors, ScriptedWalkerSpeedIsRangeChecked) {
  // speed 1e300 passed and then hung the run (the walk along the looped path never used up the distance)
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\npeople:\n  - {kind: scripted, waypoints: [[0, 1], [1, 1]], speed: 1e300}\n"),
            "w.yaml:4: 'people[0].speed' must be in [0.01, 10], got 1e300");
}

TEST(WorldErrors, ReflectivitiesAreInZeroOne) {
  // doors, furniture and markers were checked; walls and segments were not
  EXPECT_EQ(errorOf("wall_reflectivity: -5\nwalls:\n  - [[0,0],[1,0]]\n"),
            "w.yaml:1: 'wall_reflectivity' must be in [0, 1], got -5");
  EXPECT_EQ(errorOf("wall_reflectivity: 7\nwalls:\n  - [[0,0],[1,0]]\n"),
            "w.yaml:1: 'wall_reflectivity' must be in [0, 1], got 7");
  EXPECT_EQ(errorOf("segments:\n  - [0, 0, 1, 0, -3]\n"), "w.yaml:2: 'segments[0][4]' must be in [0, 1], got -3");
  EXPECT_EQ(errorOf("walls:\n  - [[0,0],[1,0]]\nmarkers:\n  - {position: [0, 0], reflectivity: 2}\n"),
            "w.yaml:4: 'markers[0].reflectivity' must be in [0, 1], got 2");
}

TEST(Occupancy, SinglePixelGivesUnitSquare) {
  OccupancyImage img{3, 3, std::vector<std::uint8_t>(9, 255)};
  img.pixels[1 * 3 + 2] = 0;  // row 1 (middle), column 2
  const auto segs = occupancyToSegments(img, 0.5, {-1.0, -2.0, 0.0}, 0.65, false, 0.3F);
  ASSERT_EQ(segs.size(), 4u);
  // column 2, map row 1 -> square [0, 0.5] x [-1.5, -1.0]
  double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
  for (const auto& s : segs)
    for (const Vec2 p : {s.a, s.b}) {
      xmin = std::min(xmin, p.x), xmax = std::max(xmax, p.x);
      ymin = std::min(ymin, p.y), ymax = std::max(ymax, p.y);
    }
  EXPECT_DOUBLE_EQ(xmin, 0.0);
  EXPECT_DOUBLE_EQ(xmax, 0.5);
  EXPECT_DOUBLE_EQ(ymin, -1.5);
  EXPECT_DOUBLE_EQ(ymax, -1.0);
}

TEST(Occupancy, RunsAreMergedAndNegateWorks) {
  OccupancyImage img{4, 2, {0, 0, 0, 255, 255, 255, 255, 255}};  // top row: 3 occupied
  EXPECT_EQ(occupancyToSegments(img, 1.0, {}, 0.65, false, 0.3F).size(), 4u);
  // negated: white is occupied -> 5 cells in an L shape: 6 boundary runs
  EXPECT_EQ(occupancyToSegments(img, 1.0, {}, 0.65, true, 0.3F).size(), 6u);
}

TEST(Occupancy, MapServerYamlWithPgmAndPng) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "cairn_sim_test_world_map";
  fs::create_directories(dir);
  {
    std::ofstream pgm(dir / "m.pgm", std::ios::binary);
    pgm << "P5\n# comment\n4 2\n255\n";
    const unsigned char px[8] = {0, 0, 0, 254, 254, 254, 254, 254};
    pgm.write(reinterpret_cast<const char*>(px), 8);
  }
  {
    std::ofstream y(dir / "m.yaml");
    y << "image: m.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  }
  {
    std::ofstream w(dir / "w.yaml");
    w << "map: m.yaml\n";
  }
  const World w = loadWorld((dir / "w.yaml").string());
  ASSERT_EQ(w.walls.size(), 4u);
  EXPECT_NEAR(w.bounds_min.x, 1.0, 1e-12);
  EXPECT_NEAR(w.bounds_min.y, 2.1, 1e-12);
  EXPECT_NEAR(w.bounds_max.x, 1.3, 1e-12);
  EXPECT_NEAR(w.bounds_max.y, 2.2, 1e-12);

  // PNG (3x3 grey, centre black) shipped as test data, referenced inline
#if CAIRN_SIM_HAVE_PNG
  const std::string png = std::string(CAIRN_SOURCE_ROOT) + "/components/sim/test/data/dot3x3.png";
  const World wp = parseWorld("map: {image: " + png + ", resolution: 1.0, origin: [0, 0, 0]}\n", "inline.yaml");
  ASSERT_EQ(wp.walls.size(), 4u);
  EXPECT_NEAR(wp.bounds_min.x, 1.0, 1e-12);
  EXPECT_NEAR(wp.bounds_max.y, 2.0, 1e-12);
#endif

  // missing image -> error names the map yaml and the image key line
  {
    std::ofstream y(dir / "bad.yaml");
    y << "resolution: 0.1\nimage: nothere.pgm\norigin: [0, 0, 0]\n";
  }
  try {
    parseWorld("map: " + (dir / "bad.yaml").string() + "\n", "w2.yaml");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir / "bad.yaml").string());
    EXPECT_EQ(e.line(), 2);
  }
}

TEST(Occupancy, PgmHeaderSizeIsCheckedAgainstTheFileBeforeAllocating) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "cairn_sim_test_world_pgm";
  fs::create_directories(dir);
  auto errorFor = [&](const std::string& name, const std::string& bytes) -> std::string {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    try {
      readImage((dir / name).string());
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string p = dir.string() + "/";
  // 10^10 pixels claimed, 2 bytes present: this allocated until the process was killed
  EXPECT_EQ(errorFor("big.pgm", std::string("P5\n100000 100000\n255\n") + std::string(2, '\0')),
            p + "big.pgm:0: image of 100000 x 100000 pixels is larger than 400000000 pixels");
  EXPECT_EQ(errorFor("p5.pgm", std::string("P5\n10000 10000\n255\n") + std::string(2, '\0')),
            p + "p5.pgm:0: truncated PGM data: the header says 10000 x 10000 pixels, the file has 2 data bytes");
  EXPECT_EQ(errorFor("p2.pgm", "P2\n3 3\n255\n0 0 0\n"),
            p + "p2.pgm:0: truncated PGM data: the header says 3 x 3 pixels, the file has 7 data bytes");
  EXPECT_EQ(errorFor("ok.pgm", "P2\n2 1\n255\n0 255"), "no error");
}

TEST(Occupancy, MapServerValuesAreRangeChecked) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "cairn_sim_test_world_map_values";
  fs::create_directories(dir);
  std::ofstream(dir / "m.pgm") << "P2\n2 1\n255\n0 255\n";
  auto errorWith = [&](const std::string& line) -> std::string {
    std::ofstream(dir / "m.yaml") << "image: m.pgm\norigin: [0, 0, 0]\n" << line << "\n";
    try {
      parseWorld("map: " + (dir / "m.yaml").string() + "\n", "w.yaml");
    } catch (const InputError& e) {
      return std::string(e.what()).substr(dir.string().size() + 1);
    }
    return "no error";
  };
  // were accepted (occupied_thresh 2: every pixel free, reported as "no geometry"; negate 5 as 1)
  EXPECT_EQ(errorWith("resolution: 0.05\noccupied_thresh: 2"), "m.yaml:4: 'occupied_thresh' must be in [0, 1], got 2");
  EXPECT_EQ(errorWith("resolution: 0.05\noccupied_thresh: -1"), "m.yaml:4: 'occupied_thresh' must be in [0, 1], got -1");
  EXPECT_EQ(errorWith("resolution: 0.05\nfree_thresh: 3"), "m.yaml:4: 'free_thresh' must be in [0, 1], got 3");
  EXPECT_EQ(errorWith("resolution: 0.05\nnegate: 5"), "m.yaml:4: 'negate' must be an integer in [0, 1], got 5");
  EXPECT_EQ(errorWith("resolution: 1e-300"), "m.yaml:3: 'resolution' must be in [0.001, 100], got 1e-300");
  EXPECT_EQ(errorWith("resolution: 0.05\nmode: bogus"), "m.yaml:4: 'mode' must be trinary, scale or raw, got 'bogus'");
  EXPECT_EQ(errorWith("resolution: 0.05\nnegate: 1\nmode: trinary\nfree_thresh: 0.2"), "no error");
  // a directory as the map file gave a raw "basic_filebuf::underflow" error without a place
  try {
    parseWorld("name: x\nmap: " + dir.string() + "\n", "w.yaml");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "w.yaml:2: map file '" + dir.string() + "' is a directory, not a file");
  }
}

TEST(World, ShippedWorldsMatchTheirSpecification) {
  for (const auto& name : shippedWorlds()) {
    const World w = loadWorld(resolveWorldPath(name));
    EXPECT_EQ(w.name, name);
    EXPECT_GT(w.walls.size(), 10u) << name;
    EXPECT_FALSE(w.doors.empty()) << name;
    EXPECT_FALSE(w.furniture.empty()) << name;
    EXPECT_EQ(w.regionAt({w.robot_start.x, w.robot_start.y}).empty(), false) << name;
  }
  const World office = loadWorld(resolveWorldPath("office"));
  EXPECT_DOUBLE_EQ(office.bounds_max.x - office.bounds_min.x, 50.0);
  EXPECT_DOUBLE_EQ(office.bounds_max.y - office.bounds_min.y, 25.0);
  bool table_legs_only = false;
  for (const auto& f : office.furniture) table_legs_only |= f.name == "meeting_table" && f.legs_only;
  EXPECT_TRUE(table_legs_only);
  // corridor widths 1.1 .. 2.1 m
  for (const char* c : {"corridor", "corridor_south", "corridor_north"}) {
    const Region* r = office.region(c);
    ASSERT_NE(r, nullptr);
    const double wx = r->polygon[2].x - r->polygon[0].x, wy = r->polygon[2].y - r->polygon[0].y;
    EXPECT_GE(std::min(wx, wy), 1.1 - 1e-9) << c;
    EXPECT_LE(std::min(wx, wy), 2.1 + 1e-9) << c;
  }
  const World apt = loadWorld(resolveWorldPath("apartment"));
  for (const char* room : {"hallway", "bedroom", "living_room", "kitchen"}) EXPECT_NE(apt.region(room), nullptr) << room;
  const World wh = loadWorld(resolveWorldPath("warehouse"));
  EXPECT_DOUBLE_EQ((wh.bounds_max.x - wh.bounds_min.x) * (wh.bounds_max.y - wh.bounds_min.y), 2500.0);
  int rooms = 0;
  for (const auto& r : wh.regions) rooms += r.name.rfind("room_", 0) == 0;
  EXPECT_EQ(rooms, 4);
  EXPECT_FALSE(wh.markers.empty());
  EXPECT_THROW(resolveWorldPath("no_such_world"), InputError);
}

TEST(Occupancy, RealMapServerMapOfTheAtcMall) {
  // The ATC shopping-centre map (Stüde's CoPA-Map data): a real map_server PNG + YAML pair.
#if !CAIRN_SIM_HAVE_PNG
  GTEST_SKIP() << "built without libpng";
#endif
  const std::string map = std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/atc_map.yaml";
  const World w = parseWorld("map: " + map + "\n", "/tmp/atc.yaml");
  EXPECT_EQ(w.walls.size(), 25934u);
  // every wall lies inside the image extent: origin (-60, -40), 2800 x 1200 pixels at 0.05 m
  EXPECT_GE(w.bounds_min.x, -60.0);
  EXPECT_GE(w.bounds_min.y, -40.0);
  EXPECT_LE(w.bounds_max.x, -60.0 + 2800 * 0.05);
  EXPECT_LE(w.bounds_max.y, -40.0 + 1200 * 0.05);
  for (const auto& s : w.walls) {
    // axis-aligned pixel edges on the 5 cm lattice
    EXPECT_TRUE(s.a.x == s.b.x || s.a.y == s.b.y);
    const double gx = (s.a.x + 60.0) / 0.05, gy = (s.a.y + 40.0) / 0.05;
    ASSERT_NEAR(gx, std::round(gx), 1e-6);
    ASSERT_NEAR(gy, std::round(gy), 1e-6);
  }
}

TEST(WorldErrors, RandomMutationsGiveWorldsOrInputErrorsOnly) {
  // Seeded mutations of a valid world: every outcome is a world or an InputError with file:line, never
  // another exception or a crash.
  Rng rng(17);
  const std::string base = kWorld;
  const char alphabet[] = "-0123456789.,:[]{} \nabtxy#";
  int ok = 0, errors = 0;
  for (int k = 0; k < 3000; ++k) {
    std::string s = base;
    const int edits = 1 + static_cast<int>(rng.uniform() * 3);
    for (int e = 0; e < edits; ++e) {
      const std::size_t pos = static_cast<std::size_t>(rng.uniform() * s.size());
      if (rng.uniform() < 0.5) s[pos] = alphabet[static_cast<std::size_t>(rng.uniform() * (sizeof alphabet - 1))];
      else s.erase(pos, 1 + static_cast<std::size_t>(rng.uniform() * 6));
    }
    try {
      const World w = parseWorld(s, "m.yaml");
      ++ok;
      for (double t : {0.0, 15.0, 1e5}) {  // schedules must be usable whatever was parsed
        std::vector<Segment> segs;
        std::vector<Circle> circles;
        w.dynamicGeometry(t, segs, circles);
      }
    } catch (const InputError& e) {
      ++errors;
      ASSERT_EQ(std::string(e.what()).rfind("m.yaml:", 0), 0u) << e.what();
    }
  }
  EXPECT_GT(ok, 100);
  EXPECT_GT(errors, 300);
}
