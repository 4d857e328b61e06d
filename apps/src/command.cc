#include "fivebar/io/command.h"
#include "fivebar/io/output.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

namespace fivebar::io {
namespace {

// constructed on first use, so that registration from any translation unit's static
// initializers is safe
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace

bool register_command(Command command) {
  registry().push_back(std::move(command));
  return true;
}

std::vector<Command> registered_commands() {
  std::vector<Command> commands = registry();
  std::sort(commands.begin(), commands.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  return commands;
}

void print_written(const std::string& dir, const std::vector<std::string>& names) {
  std::cout << "  wrote " << dir << "/:";
  for (const std::string& name : names) std::cout << " " << name;
  std::cout << std::endl;
}

int finish_run(OutputDir* out, const std::function<void()>& report) {
  const std::vector<std::string> written = out->commit();
  report();
  print_written(out->dir(), written);
  return 0;
}

void warn(const std::string& message) { std::cerr << "fivebar: warning: " << message << "\n"; }

namespace {
double seconds_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Progress::Progress(std::string label, double total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), start_(seconds_now()),
      terminal_(::isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() {
  if (shown_) std::cerr << "\r\033[K" << std::flush;
}

void Progress::update(double done) {
  if (!terminal_) return;
  const double now = seconds_now();
  if (now - start_ < 2.0 || now - last_ < 0.25) return;
  last_ = now;
  shown_ = true;
  const double pct = total_ > 0 ? 100.0 * done / total_ : 0.0;
  char buf[160];
  std::snprintf(buf, sizeof buf, "\r\033[K%s: %3.0f%% (%.4g / %.4g%s%s)", label_.c_str(), pct,
                done, total_, unit_.empty() ? "" : " ", unit_.c_str());
  std::cerr << buf << std::flush;
}

}  // namespace fivebar::io
