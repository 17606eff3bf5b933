#include "cairn/copa_map/io.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

namespace cairn::copa_map {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

std::ifstream openInputFile(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, 0, "cannot open " + what + ": is a directory");
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open " + what);
  return in;
}

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

bool parseDouble(const std::string& s, double& v) {
  if (s.empty()) return false;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

}  // namespace

int CsvTable::column(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

CsvTable readCsv(const std::string& path) {
  std::ifstream in = openInputFile(path, "file");
  CsvTable t;
  std::string line;
  long lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (!trim(line).empty()) break;
  }
  if (trim(line).empty()) throw InputError(path, lineno, "empty file (no header)");
  t.header = split(trim(line));
  std::vector<double> values;
  const std::size_t nc = t.header.size();
  long rows = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty()) continue;
    const auto cells = split(trim(line));
    if (cells.size() != nc)
      throw InputError(path, lineno, "expected " + std::to_string(nc) + " columns, got " + std::to_string(cells.size()));
    for (std::size_t c = 0; c < nc; ++c) {
      double v;
      if (!parseDouble(cells[c], v)) throw InputError(path, lineno, "non-numeric value '" + cells[c] + "' in column " + t.header[c]);
      if (!std::isfinite(v)) throw InputError(path, lineno, "NaN or Inf in column " + t.header[c]);
      values.push_back(v);
    }
    t.lines.push_back(lineno);
    ++rows;
  }
  t.data.resize(rows, static_cast<Eigen::Index>(nc));
  for (long r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < nc; ++c) t.data(r, static_cast<Eigen::Index>(c)) = values[static_cast<std::size_t>(r) * nc + c];
  return t;
}

GridData readGridCsv(const std::string& path, bool require_y) {
  const CsvTable t = readCsv(path);
  const int c1 = t.column("x1"), c2 = t.column("x2"), ct = t.column("t"), cy = t.column("y");
  const int cd = t.column("duration");
  if (c1 < 0 || c2 < 0 || ct < 0) throw InputError(path, 1, "missing column(s): need x1, x2, t");
  if (require_y && cy < 0) throw InputError(path, 1, "missing column y");
  if (t.data.rows() == 0) throw InputError(path, 2, "no data rows");
  GridData g;
  g.X.resize(t.data.rows(), 3);
  g.X.col(0) = t.data.col(c1);
  g.X.col(1) = t.data.col(c2);
  g.X.col(2) = t.data.col(ct);
  if (cy >= 0) {
    g.y = t.data.col(cy);
    if (require_y)
      for (Eigen::Index i = 0; i < g.y.size(); ++i)
        if (g.y[i] < 0) throw InputError(path, t.lines[static_cast<std::size_t>(i)], "negative rate y");
  }
  if (cd >= 0) {
    g.durations = t.data.col(cd);
    for (Eigen::Index i = 0; i < g.durations.size(); ++i)
      if (g.durations[i] < 0)
        throw InputError(path, t.lines[static_cast<std::size_t>(i)], "negative duration");
  }
  return g;
}

Eigen::MatrixXd readInducingCsv(const std::string& path) {
  const CsvTable t = readCsv(path);
  int c1 = t.column("x_z1"), c2 = t.column("x_z2"), ct = t.column("t_z");
  if (c1 < 0) {
    c1 = t.column("x1");
    c2 = t.column("x2");
    ct = t.column("t");
  }
  if (c1 < 0 || c2 < 0 || ct < 0) throw InputError(path, 1, "missing column(s): need x_z1, x_z2, t_z");
  if (t.data.rows() == 0) throw InputError(path, 2, "no inducing points");
  Eigen::MatrixXd Z(t.data.rows(), 3);
  Z.col(0) = t.data.col(c1);
  Z.col(1) = t.data.col(c2);
  Z.col(2) = t.data.col(ct);
  return Z;
}

void saveModel(const CopaMap& model, const std::string& path) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(path, 0, "cannot write model file");
    out << std::setprecision(17);
    const SvgpModel& m = model.model();
    out << "cairn-copa-model " << kModelFileVersion << "\n";
    out << "y_mean " << model.yMean() << "\ny_scale " << model.yScale() << "\n";
    out << "cell_size " << model.cellSize() << "\ntime_bin " << model.timeBin() << "\n";
    out << "jitter " << m.jitter() << "\n";
    const auto& lik = m.likelihood();
    double lp = 0;
    if (auto* h = dynamic_cast<const HeteroscedasticGaussianLikelihood*>(&lik)) lp = h->ghOrder();
    if (auto* g = dynamic_cast<const GaussianLikelihood*>(&lik)) lp = g->variance();
    if (dynamic_cast<const PoissonLikelihood*>(&lik)) lp = 20;
    out << "likelihood " << lik.type() << " " << lp << "\n";
    out << "latents " << m.latents().size() << "\n";
    for (const auto& l : m.latents()) {
      const Eigen::VectorXd p = l.kernel->params();
      out << "kernel " << l.kernel->type() << " " << p.size();
      for (Eigen::Index i = 0; i < p.size(); ++i) out << " " << p[i];
      out << "\ninducing " << l.Z.rows() << "\n";
      for (Eigen::Index i = 0; i < l.Z.rows(); ++i) out << l.Z(i, 0) << " " << l.Z(i, 1) << " " << l.Z(i, 2) << "\n";
      out << "q_mu\n";
      for (Eigen::Index i = 0; i < l.mu.size(); ++i) out << l.mu[i] << (i + 1 == l.mu.size() ? "\n" : " ");
      out << "q_sqrt\n";
      for (Eigen::Index i = 0; i < l.L.rows(); ++i) {
        for (Eigen::Index j = 0; j <= i; ++j) out << l.L(i, j) << (j == i ? "\n" : " ");
      }
    }
    out << "end\n";
    if (!out) throw InputError(path, 0, "write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw InputError(path, 0, "cannot rename temporary model file");
}

namespace {

class TokenReader {
 public:
  TokenReader(const std::string& path) : path_(path), in_(openInputFile(path, "model file")) {}
  std::string word() {
    std::string w;
    while (true) {
      int c = in_.get();
      if (c == EOF) {
        if (w.empty()) throw InputError(path_, line_, "unexpected end of model file (truncated?)");
        return w;
      }
      if (c == '\n') {
        if (!w.empty()) {
          in_.unget();
          return w;
        }
        ++line_;
        continue;
      }
      if (c == ' ' || c == '\t' || c == '\r') {
        if (!w.empty()) return w;
        continue;
      }
      w.push_back(static_cast<char>(c));
    }
  }
  double number() {
    const std::string w = word();
    double v;
    char* end = nullptr;
    v = std::strtod(w.c_str(), &end);
    if (end != w.c_str() + w.size() || !std::isfinite(v)) throw InputError(path_, line_, "corrupt model file: bad number '" + w + "'");
    return v;
  }
  long integer(long lo, long hi) {
    const double v = number();
    if (v != std::floor(v) || v < lo || v > hi) throw InputError(path_, line_, "corrupt model file: bad count");
    return static_cast<long>(v);
  }
  void expect(const std::string& key) {
    const std::string w = word();
    if (w != key) throw InputError(path_, line_, "corrupt model file: expected '" + key + "', found '" + w + "'");
  }
  long line() const { return line_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ifstream in_;
  long line_ = 1;
};

}  // namespace

CopaMap loadModel(const std::string& path) {
  TokenReader r(path);
  const std::string magic = r.word();
  if (magic != "cairn-copa-model") throw InputError(path, 1, "not a cairn CoPA-Map model file");
  const long version = r.integer(0, 1000000);
  if (version != kModelFileVersion)
    throw InputError(path, 1, "model file version " + std::to_string(version) + " is not supported (this build reads version " +
                                  std::to_string(kModelFileVersion) + ")");
  CopaMap cm;
  r.expect("y_mean");
  const double ym = r.number();
  r.expect("y_scale");
  const double ys = r.number();
  if (!(ys > 0)) throw InputError(path, r.line(), "corrupt model file: y_scale must be > 0");
  cm.setStandardization(ym, ys);
  r.expect("cell_size");
  const double cs = r.number();
  r.expect("time_bin");
  const double tb = r.number();
  if (!(cs > 0) || !(tb > 0)) throw InputError(path, r.line(), "corrupt model file: grid sizes must be > 0");
  cm.setGrid(cs, tb);
  r.expect("jitter");
  const double jitter = r.number();
  r.expect("likelihood");
  const std::string lt = r.word();
  const double lp = r.number();
  std::unique_ptr<Likelihood> lik;
  try {
    lik = makeLikelihood(lt, lp);
  } catch (const std::exception& e) {
    throw InputError(path, r.line(), e.what());
  }
  r.expect("latents");
  const long nl = r.integer(1, 2);
  std::vector<LatentGp> lat;
  for (long k = 0; k < nl; ++k) {
    r.expect("kernel");
    const std::string kt = r.word();
    const long np = r.integer(0, 1000);
    Eigen::VectorXd p(np);
    for (long i = 0; i < np; ++i) p[i] = r.number();
    LatentGp l;
    try {
      l.kernel = makeKernel(kt, p);
    } catch (const std::exception& e) {
      throw InputError(path, r.line(), e.what());
    }
    r.expect("inducing");
    const long m = r.integer(1, 200000);
    l.Z.resize(m, 3);
    for (long i = 0; i < m; ++i)
      for (int d = 0; d < 3; ++d) l.Z(i, d) = r.number();
    r.expect("q_mu");
    l.mu.resize(m);
    for (long i = 0; i < m; ++i) l.mu[i] = r.number();
    r.expect("q_sqrt");
    l.L = Eigen::MatrixXd::Zero(m, m);
    for (long i = 0; i < m; ++i)
      for (long j = 0; j <= i; ++j) l.L(i, j) = r.number();
    lat.push_back(std::move(l));
  }
  r.expect("end");
  try {
    cm.setModel(SvgpModel(std::move(lat), std::move(lik), jitter));
  } catch (const std::exception& e) {
    throw InputError(path, r.line(), e.what());
  }
  return cm;
}

}  // namespace cairn::copa_map
