#include "fivebar/io/loads.h"

#include <muParser.h>

#include <cmath>
#include <utility>
#include <vector>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/scene.h"

namespace fivebar::io {

// what copies share: the expressions, which of them are constant, and their constant values
struct LoadExpressions::Compiled {
  std::array<std::string, 4> expressions;
  std::array<bool, 4> constant{};
  std::array<double, 4> value{};  // the value of each constant expression
  double F_angle = 0;
  std::string file;  // the scene the expressions come from
};

// one parser per non-constant expression, all bound to the variable t_ of this object (which
// therefore never moves: it lives behind a unique_ptr). Used by one thread at a time.
class LoadExpressions::Evaluator {
 public:
  explicit Evaluator(const Compiled& c) {
    for (int i = 0; i < 4; ++i) {
      if (!c.constant[i]) parsers_[i] = make_parser(c.expressions[i], &t_);
    }
  }

  // a parser for `expression` with the variable t at *t and the constant pi; compiled to
  // bytecode by a first evaluation. Throws mu::ParserError.
  static std::unique_ptr<mu::Parser> make_parser(const std::string& expression, double* t) {
    auto parser = std::make_unique<mu::Parser>();
    parser->DefineConst("pi", M_PI);
    parser->DefineVar("t", t);
    parser->SetExpr(expression);
    parser->Eval();
    return parser;
  }

  Loads<double> eval(const Compiled& c, double t) {
    std::array<double, 4> v = c.value;
    t_ = t;
    try {
      for (int i = 0; i < 4; ++i) {
        if (parsers_[i]) v[i] = parsers_[i]->Eval();
      }
    } catch (const mu::ParserError&) {
      v.fill(std::nan(""));
    }
    return {v[kM1], v[kM2], v[kM3], v[kF], c.F_angle};
  }

 private:
  double t_ = 0;
  std::array<std::unique_ptr<mu::Parser>, 4> parsers_;
};

namespace {

// parsers private to the calling thread, for an object whose own parsers another thread is
// using; a handful are kept, keyed by the shared compiled state (which they keep alive)
template <typename Compiled, typename Evaluator>
Evaluator& thread_evaluator(const std::shared_ptr<const Compiled>& compiled) {
  constexpr size_t kCached = 8;
  thread_local std::vector<std::pair<std::shared_ptr<const Compiled>, std::unique_ptr<Evaluator>>>
      cache;
  for (auto& entry : cache) {
    if (entry.first == compiled) return *entry.second;
  }
  if (cache.size() >= kCached) cache.erase(cache.begin());
  cache.emplace_back(compiled, std::make_unique<Evaluator>(*compiled));
  return *cache.back().second;
}

}  // namespace

LoadExpressions::LoadExpressions(const std::array<std::string, 4>& expressions, double F_angle,
                                 const std::string& file) {
  auto c = std::make_shared<Compiled>();
  c->expressions = expressions;
  c->F_angle = F_angle;
  c->file = file;
  for (int i = 0; i < 4; ++i) {
    const std::string key = std::string("loads.") + kNames[i];
    double t = 0;
    try {
      auto parser = Evaluator::make_parser(expressions[i], &t);
      // constant: no variable used, evaluate once
      c->constant[i] = parser->GetUsedVar().empty();
      // evaluable and finite at two times, so that typos surface now and not mid-run
      for (double probe : {0.0, 1.0}) {
        t = probe;
        const double v = parser->Eval();
        if (!std::isfinite(v)) {
          throw InputError(file, key,
                           "'" + expressions[i] + "' is not finite at t = " + format_double(probe) +
                               " (" + format_double(v) + ")");
        }
        const std::string implausible = limit_problem(key, v);
        if (!implausible.empty()) {
          throw InputError(
              file, key,
              "'" + expressions[i] + "' at t = " + format_double(probe) + ": " + implausible);
        }
        if (c->constant[i]) c->value[i] = v;
      }
    } catch (const mu::ParserError& e) {
      throw InputError(file, key, "'" + expressions[i] + "': " + e.GetMsg());
    }
  }
  compiled_ = std::move(c);
  evaluator_ = std::make_unique<Evaluator>(*compiled_);
}

LoadExpressions::LoadExpressions(const Scene& scene)
    : LoadExpressions({scene.M1, scene.M2, scene.M3, scene.F}, scene.F_angle, scene.path) {}

LoadExpressions::LoadExpressions(const LoadExpressions& other)
    : compiled_(other.compiled_), evaluator_(std::make_unique<Evaluator>(*compiled_)) {}

LoadExpressions& LoadExpressions::operator=(const LoadExpressions& other) {
  if (this != &other) {
    compiled_ = other.compiled_;
    evaluator_ = std::make_unique<Evaluator>(*compiled_);
  }
  return *this;
}

LoadExpressions::LoadExpressions(LoadExpressions&& other) noexcept
    : compiled_(std::move(other.compiled_)), evaluator_(std::move(other.evaluator_)) {}

LoadExpressions& LoadExpressions::operator=(LoadExpressions&& other) noexcept {
  compiled_ = std::move(other.compiled_);
  evaluator_ = std::move(other.evaluator_);
  return *this;
}

LoadExpressions::~LoadExpressions() = default;

Loads<double> LoadExpressions::operator()(double t) const {
  if (!busy_.test_and_set(std::memory_order_acquire)) {
    const Loads<double> out = evaluator_->eval(*compiled_, t);
    busy_.clear(std::memory_order_release);
    return out;
  }
  // another thread is evaluating with this object's parsers
  return thread_evaluator<Compiled, Evaluator>(compiled_).eval(*compiled_, t);
}

sim::LoadFunction LoadExpressions::function() const {
  return [self = *this](double t) { return self(t); };
}

sim::FourBarLoadFunction LoadExpressions::four_bar_function() const {
  return [self = *this](double t) {
    const Loads<double> L = self(t);
    return FourBarLoads{L.M1, L.M3, L.F, L.F_angle};
  };
}

void LoadExpressions::require_finite(const std::vector<double>& times) const {
  for (double t : times) {
    const Loads<double> L = (*this)(t);
    const double v[4] = {L.M1, L.M2, L.M3, L.F};
    for (int i = 0; i < 4; ++i) {
      if (std::isfinite(v[i])) continue;
      throw NumericalError(compiled_->file, std::string("loads.") + kNames[i],
                           sim::non_finite_load(kNames[i], v[i], t));
    }
  }
}

void LoadExpressions::require_finite(double duration, double step) const {
  // a grid of more than kMaxGrid points (which the commands refuse as too many rows before
  // they run) is not walked
  constexpr double kMaxGrid = 1e8;
  std::vector<double> times;
  const double n = std::ceil(duration / step - 1e-9);
  if (n >= 0 && n < kMaxGrid) {
    for (long i = 0; i < static_cast<long>(n); ++i) times.push_back(static_cast<double>(i) * step);
  }
  times.push_back(duration);
  require_finite(times);
}

const std::array<std::string, 4>& LoadExpressions::expressions() const {
  return compiled_->expressions;
}

bool LoadExpressions::constant(int which) const { return compiled_->constant.at(which); }

}  // namespace fivebar::io
