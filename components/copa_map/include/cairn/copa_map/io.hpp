// File formats of cairn_copa_map: grid CSVs (copa-map's `x1,x2,t,y` files, optional `duration`/`count`
// columns), inducing-point CSVs (`x_z1,x_z2,t_z` or `x1,x2,t`), and versioned text model files.
#pragma once

#include <Eigen/Dense>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/copa_map/copa_map.hpp"

namespace cairn::copa_map {

// Bad input with a location: what() is "<file>:<line>: <message>".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, long line, const std::string& msg)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + msg), file_(file), line_(line) {}
  const std::string& file() const { return file_; }
  long line() const { return line_; }

 private:
  std::string file_;
  long line_;
};

struct CsvTable {
  std::vector<std::string> header;
  Eigen::MatrixXd data;  // rows x columns, all values finite
  std::vector<long> lines;                    // file line of each data row (blank lines are skipped)
  int column(const std::string& name) const;  // -1 when missing
};

// Strips spaces, tabs, CR and LF at both ends (the CSV and config-file readers).
std::string trim(const std::string& s);

// Opens a file for reading; InputError(path, 0, "cannot open <what>") if it cannot be opened or is a
// directory (std::ifstream opens a directory and then reads nothing, which would look like an empty file).
std::ifstream openInputFile(const std::string& path, const std::string& what);

// Reads a numeric CSV with a header line. Every row must have the header's column count and finite numbers.
CsvTable readCsv(const std::string& path);

struct GridData {
  Eigen::MatrixXd X;          // n x 3: x1, x2, t
  Eigen::VectorXd y;          // rates (may be empty for point files)
  Eigen::VectorXd durations;  // Δ_i if a `duration` column exists, else empty
};

// Grid file: columns x1, x2, t and (if require_y) y (a rate, must be >= 0); optional `duration` (must be >=
// 0). Empty files are errors.
GridData readGridCsv(const std::string& path, bool require_y = true);
// Inducing points: columns x_z1, x_z2, t_z (copa-map) or x1, x2, t.
Eigen::MatrixXd readInducingCsv(const std::string& path);

// Model files: "cairn-copa-model <version>" followed by key/value lines; a file of another version, or a
// truncated / corrupt file, raises InputError.
constexpr int kModelFileVersion = 1;
void saveModel(const CopaMap& model, const std::string& path);
CopaMap loadModel(const std::string& path);

}  // namespace cairn::copa_map
