// docs/scene.md documents every key of the scene schema (scene_keys), and no key it does not
// accept: the first column of its key tables, `a.b`, or `a.M1.x`, `a.M2.x` for several keys.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "fivebar/io/scene.h"

namespace fivebar::io {
namespace {

// the keys named in the first cell of the table rows of docs/scene.md
std::set<std::string> documented_keys() {
  std::ifstream in(std::string(FIVEBAR_SOURCE_DIR) + "/docs/scene.md");
  EXPECT_TRUE(in) << "docs/scene.md not found";
  std::set<std::string> keys;
  const std::regex key("`([a-z_0-9]+(\\.[A-Za-z_0-9]+)*)`");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("| `", 0) != 0) continue;
    const std::string cell = line.substr(1, line.find('|', 1) - 1);
    for (std::sregex_iterator m(cell.begin(), cell.end(), key), end; m != end; ++m) {
      keys.insert((*m)[1]);
    }
  }
  return keys;
}

TEST(SceneDoc, EveryKeyOfTheSchemaIsDocumented) {
  const std::set<std::string> documented = documented_keys();
  std::vector<std::string> missing;
  for (const std::string& k : scene_keys()) {
    if (!documented.count(k)) missing.push_back(k);
  }
  EXPECT_THAT(missing, ::testing::IsEmpty()) << "keys of the schema missing from docs/scene.md";
}

TEST(SceneDoc, EveryDocumentedKeyIsInTheSchema) {
  const std::vector<std::string> all = scene_keys(/*sections=*/true);
  const std::set<std::string> schema(all.begin(), all.end());
  std::vector<std::string> unknown;
  for (const std::string& k : documented_keys()) {
    // the integrator table's names are not keys: only dotted names and top-level keys count
    if (k.find('.') == std::string::npos && k != "gravity") continue;
    if (!schema.count(k)) unknown.push_back(k);
  }
  EXPECT_THAT(unknown, ::testing::IsEmpty()) << "keys in docs/scene.md the schema refuses";
}

// the rows of docs/scene.md's plausibility table: key -> (low, high)
std::map<std::string, std::pair<double, double>> documented_limits() {
  std::ifstream in(std::string(FIVEBAR_SOURCE_DIR) + "/docs/scene.md");
  std::map<std::string, std::pair<double, double>> out;
  const std::regex row(
      R"(^\| `([a-zA-Z0-9_.]+)` \| [^|]+ \| (\[([^,]+), ([^\]]+)\]|at most (\S+)|at least (\S+)[^|]*) \|$)");
  std::string line;
  bool in_table = false;
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) in_table = line == "## Plausibility limits";
    std::smatch m;
    if (!in_table || !std::regex_match(line, m, row)) continue;
    if (m[6].matched) {
      out[m[1]] = {std::stod(m[6]), std::numeric_limits<double>::max()};
    } else {
      out[m[1]] = m[5].matched ? std::make_pair(0.0, std::stod(m[5]))
                               : std::make_pair(std::stod(m[3]), std::stod(m[4]));
    }
  }
  return out;
}

TEST(SceneDoc, PlausibilityLimitsAreTheSchemas) {
  const auto documented = documented_limits();
  ASSERT_FALSE(documented.empty()) << "no plausibility table in docs/scene.md";
  for (const std::string& k : scene_keys()) {
    const SceneLimit* l = scene_limit(k);
    const std::string m1 = k.rfind("actuators.M2.", 0) == 0 ? "actuators.M1." + k.substr(13) : k;
    auto it = documented.find(m1);
    if (l == nullptr) {
      EXPECT_EQ(it, documented.end()) << k << " is documented with a limit it does not have";
      continue;
    }
    ASSERT_NE(it, documented.end()) << k << "'s limit is not in docs/scene.md";
    EXPECT_EQ(it->second.first, l->low) << k;
    EXPECT_EQ(it->second.second, l->high) << k;
  }
}

}  // namespace
}  // namespace fivebar::io
