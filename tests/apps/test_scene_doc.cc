// docs/scene.md documents every key of the scene schema (scene_keys), and no key it does not
// accept: the first column of its key tables, `a.b`, or `a.M1.x`, `a.M2.x` for several keys.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
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

}  // namespace
}  // namespace fivebar::io
