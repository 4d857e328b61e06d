#include "fivebar/io/output.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <csignal>
#include <memory>
#include <mutex>
#include <system_error>
#include <vector>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/model/dynamics.h"

namespace fivebar::io {
namespace fs = std::filesystem;

namespace {

// a FILE* that closes itself
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_for_writing(const std::string& path) {
  File f(std::fopen(path.c_str(), "wb"));
  if (!f) throw InputError(path, "(write)", std::string("cannot create: ") + std::strerror(errno));
  return f;
}

void close_checked(File f, const std::string& path) {
  std::FILE* raw = f.release();
  const bool failed = std::ferror(raw) != 0;
  if (std::fclose(raw) != 0 || failed) {
    throw InputError(path, "(write)", std::string("write failed: ") + std::strerror(errno));
  }
}

// appends x in shortest round-trip form and a separator
inline void append_number(std::string* line, double x, char sep) {
  line->append(format_double(x));
  line->push_back(sep);
}

}  // namespace

double* row_values(const sim::Row& r, double* out, const TrajectoryLayout& layout) {
  *out++ = r.t;
  for (const auto* a : {&r.theta, &r.omega, &r.alpha}) out = std::copy_n(a->begin(), layout.links, out);
  *out++ = r.M1;
  if (layout.drives > 1) *out++ = r.M2;
  for (const auto* a : {&r.N, &r.Mf}) out = std::copy_n(a->begin(), layout.joints, out);
  for (double x : {r.P_diss, r.E_diss, r.W_in, r.W_ext}) *out++ = x;
  return out;
}

std::vector<std::string> trajectory_columns(const TrajectoryLayout& layout) {
  std::vector<std::string> c = {"t"};
  for (const char* q : {"theta", "omega", "alpha"}) {
    for (int i = 1; i <= layout.links; ++i) c.push_back(q + std::to_string(i));
  }
  for (int i = 1; i <= layout.drives; ++i) c.push_back("M" + std::to_string(i));
  for (const char* q : {"N", "Mf"}) {
    for (int k = 1; k <= layout.joints; ++k) c.push_back(q + std::to_string(k));
  }
  for (const char* q : {"P_diss", "E_diss", "W_in", "W_ext"}) c.push_back(q);
  return c;
}

const std::vector<std::string>& trajectory_columns() {
  static const std::vector<std::string> columns = trajectory_columns(TrajectoryLayout{});
  return columns;
}

std::vector<Column> rest_columns(const std::vector<sim::Row>& rows,
                                 const TrajectoryLayout& layout) {
  std::vector<Column> c = {{"at_rest", {}}};
  for (int k = 1; k <= layout.joints; ++k) c.push_back({"stuck" + std::to_string(k), {}});
  const int ranges = 2 * layout.drives;  // min and max of each drive
  for (int i = 0; i < ranges; ++i) {
    c.push_back({"M" + std::to_string(i / 2 + 1) + (i % 2 ? "_hold_max" : "_hold_min"), {}});
  }
  for (const sim::Row& r : rows) {
    c[0].values.push_back(r.at_rest(layout.drives) ? 1.0 : 0.0);
    for (int k = 0; k < layout.joints; ++k) {
      c[1 + k].values.push_back(r.mode[k] == kStuck ? 1.0 : 0.0);
    }
    for (int i = 0; i < ranges; ++i) c[1 + layout.joints + i].values.push_back(r.hold_range[i]);
  }
  return c;
}

void write_trajectory_csv(const std::string& path, const std::vector<sim::Row>& rows,
                          const std::vector<Column>& extra, const TrajectoryLayout& layout) {
  for (const Column& c : extra) {
    if (c.values.size() != rows.size()) {
      throw InputError(path, c.name,
                       "internal: column has " + std::to_string(c.values.size()) + " values for " +
                           std::to_string(rows.size()) + " rows");
    }
  }
  File f = open_for_writing(path);
  std::string line;
  for (const std::string& name : trajectory_columns(layout)) line += name + ",";
  for (const Column& c : extra) line += c.name + ",";
  line.back() = '\n';
  std::fputs(line.c_str(), f.get());

  std::vector<double> values(trajectory_columns(layout).size());
  for (size_t i = 0; i < rows.size(); ++i) {
    row_values(rows[i], values.data(), layout);
    line.clear();
    line.append(format_grid_value(values[0]));  // 0.476, not 476 * 0.001 = 0.47600000000000003
    line.push_back(',');
    for (size_t j = 1; j < values.size(); ++j) append_number(&line, values[j], ',');
    for (const Column& c : extra) append_number(&line, c.values[i], ',');
    line.back() = '\n';
    std::fwrite(line.data(), 1, line.size(), f.get());
  }
  close_checked(std::move(f), path);
}

void write_text_file(const std::string& path, const std::string& text) {
  File f = open_for_writing(path);
  std::fwrite(text.data(), 1, text.size(), f.get());
  close_checked(std::move(f), path);
}

void write_json_file(const std::string& path, const Json& json) {
  write_text_file(path, json.dump(2) + "\n");
}

namespace {

// staging directories of the live OutputDirs: an interrupted run (SIGINT, SIGTERM) removes them
// before it dies, so no half-written output is left behind
std::mutex g_staging_mutex;
std::vector<std::string>* g_staging = new std::vector<std::string>;  // never destroyed

extern "C" void remove_staging_and_die(int sig) {
  for (const std::string& dir : *g_staging) {
    std::error_code ec;
    fs::remove_all(dir, ec);  // not async-signal-safe, but the process is going down anyway
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

void track_staging(const std::string& dir, bool add) {
  std::lock_guard<std::mutex> lock(g_staging_mutex);
  if (add) {
    static const bool installed = [] {
      std::signal(SIGINT, remove_staging_and_die);
      std::signal(SIGTERM, remove_staging_and_die);
      return true;
    }();
    static_cast<void>(installed);
    g_staging->push_back(dir);
  } else {
    g_staging->erase(std::remove(g_staging->begin(), g_staging->end(), dir), g_staging->end());
  }
}

}  // namespace

void OutputDir::remove_previous(const std::string& dir, const std::vector<std::string>& outputs) {
  std::error_code ec;
  for (const std::string& name : outputs) {
    const fs::path old = fs::path(dir) / name;
    if (fs::is_regular_file(old, ec) && !fs::remove(old, ec)) {
      throw InputError(old.string(), "--out", "cannot remove the previous result: " + ec.message());
    }
  }
}

OutputDir::OutputDir(const std::string& dir, const std::vector<std::string>& outputs) : dir_(dir) {
  std::error_code ec;
  created_ = !fs::exists(dir_, ec);
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    throw InputError(dir_, "--out",
                     "cannot create the output directory: " +
                         (ec ? ec.message() : "a file of that name exists"));
  }
  remove_previous(dir_, outputs);
  std::string pattern = (fs::path(dir_) / ".partial-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    throw InputError(dir_, "--out",
                     std::string("cannot create a staging directory: ") + std::strerror(errno));
  }
  staging_ = pattern;
  track_staging(staging_, true);
}

OutputDir::~OutputDir() {
  if (committed_) return;
  track_staging(staging_, false);
  std::error_code ec;
  fs::remove_all(staging_, ec);  // best effort: never throw from a destructor
  if (created_) fs::remove(dir_, ec);  // the directory this run created, when left empty
}

std::string OutputDir::file(const std::string& name) const {
  return (fs::path(staging_) / name).string();
}

std::vector<std::string> OutputDir::commit() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(staging_)) {
    if (entry.is_regular_file()) names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  // summary.json last: its presence marks a complete run
  std::stable_partition(names.begin(), names.end(),
                        [](const std::string& n) { return n != "summary.json"; });
  for (const std::string& name : names) {
    std::error_code ec;
    fs::rename(fs::path(staging_) / name, fs::path(dir_) / name, ec);
    if (ec)
      throw InputError((fs::path(dir_) / name).string(), "--out",
                       "cannot move into place: " + ec.message());
  }
  std::error_code ec;
  fs::remove_all(staging_, ec);
  track_staging(staging_, false);
  committed_ = true;
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace fivebar::io
