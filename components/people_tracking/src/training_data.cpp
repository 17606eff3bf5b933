// CSV I/O of labelled clusters (training data written by `cairn people gen-train`, read by train/eval).
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cairn/people_tracking/classifier.hpp"

namespace cairn::people_tracking {

namespace {

std::vector<std::string> splitCommas(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream is(line);
  while (std::getline(is, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::string header() {
  std::string h = "label,class,scene";
  for (const FeatureInfo& f : featureRegistry()) {
    h.push_back(',');
    h.append(f.name);
  }
  return h;
}

ObjectClass objectClassFromString(const std::string& s, const std::string& where) {
  for (int c = 0; c <= static_cast<int>(ObjectClass::kClutter); ++c)
    if (s == toString(static_cast<ObjectClass>(c))) return static_cast<ObjectClass>(c);
  throw InputError(where + ": unknown object class '" + s + "'");
}

}  // namespace

void saveLabelledClusters(const std::string& path, const std::vector<LabelledCluster>& samples) {
  std::ofstream f(path);
  if (!f) throw InputError(path + ": cannot open for writing");
  f << header() << "\n";
  f.precision(9);
  for (const LabelledCluster& s : samples) {
    f << (s.positive ? 1 : 0) << "," << toString(s.object_class) << "," << s.scene;
    for (double v : s.features) f << "," << v;
    f << "\n";
  }
  if (!f) throw InputError(path + ": write failed");
}

std::vector<LabelledCluster> loadLabelledClusters(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path + ": cannot open");
  std::string line;
  if (!std::getline(f, line)) throw InputError(path + ":1: empty file (expected the header '" + header() + "')");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != header()) throw InputError(path + ":1: header does not match feature registry version " +
                                         std::to_string(kFeatureRegistryVersion) + " ('" + header() + "')");
  std::vector<LabelledCluster> out;
  int lineno = 1;
  while (std::getline(f, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(lineno);
    const std::vector<std::string> cells = splitCommas(line);
    if (cells.size() != 3 + kNumFeatures)
      throw InputError(where + ": expected " + std::to_string(3 + kNumFeatures) + " columns, got " +
                       std::to_string(cells.size()));
    LabelledCluster s;
    if (cells[0] != "0" && cells[0] != "1") throw InputError(where + ": label must be 0 or 1, got '" + cells[0] + "'");
    s.positive = cells[0] == "1";
    s.object_class = objectClassFromString(cells[1], where);
    char* end = nullptr;
    errno = 0;
    const long scene = std::strtol(cells[2].c_str(), &end, 10);
    if (cells[2].empty() || *end != '\0' || errno) throw InputError(where + ": bad scene '" + cells[2] + "'");
    s.scene = static_cast<int>(scene);
    for (std::size_t i = 0; i < kNumFeatures; ++i) {
      const std::string& c = cells[3 + i];
      const double v = std::strtod(c.c_str(), &end);
      if (c.empty() || *end != '\0' || !std::isfinite(v))
        throw InputError(where + ": feature '" + std::string(featureRegistry()[i].name) + "' is not a finite number ('" +
                         c + "')");
      s.features[i] = v;
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace cairn::people_tracking
