// The scenario format's documentation and its parser name the same keys: every key of the tables
// in docs/scenario.md (first column, each dotted part) is one the parser accepts
// (src/sim/scenario.cpp's expect_keys lists), and every key the parser accepts is documented.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace skytrace {
namespace {

std::string read_source(const std::string& relative) {
  std::ifstream in(test::source_dir() / relative);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string joined(const std::set<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

TEST(DocsScenarioKeys, DocumentedKeysAreTheParsersKeys) {
  const std::string parser_source = read_source("src/sim/scenario.cpp");
  const std::string docs = read_source("docs/scenario.md");
  ASSERT_FALSE(parser_source.empty());
  ASSERT_FALSE(docs.empty());
  std::set<std::string> parsed;
  const std::regex call(R"(expect_keys\(\{([^}]*)\}\))");
  const std::regex quoted("\"([^\"]+)\"");
  for (auto c = std::sregex_iterator(parser_source.begin(), parser_source.end(), call); c != std::sregex_iterator(); ++c) {
    const std::string list = (*c)[1].str();
    for (auto q = std::sregex_iterator(list.begin(), list.end(), quoted); q != std::sregex_iterator(); ++q) {
      parsed.insert((*q)[1].str());
    }
  }
  ASSERT_GT(parsed.size(), 50U);  // the parser's lists were found
  std::set<std::string> documented;
  const std::regex code("`([^`]+)`");
  std::istringstream lines(docs);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("| `", 0) != 0) continue;
    const std::string first_column = line.substr(1, line.find('|', 1) - 1);
    for (auto k = std::sregex_iterator(first_column.begin(), first_column.end(), code); k != std::sregex_iterator(); ++k) {
      std::string key = (*k)[1].str();
      for (size_t at; (at = key.find("[]")) != std::string::npos;) key.erase(at, 2);
      std::istringstream parts(key);
      for (std::string part; std::getline(parts, part, '.');) documented.insert(part);
    }
  }
  std::set<std::string> undocumented, unknown;
  for (const auto& k : parsed) {
    if (!documented.count(k)) undocumented.insert(k);
  }
  for (const auto& k : documented) {
    if (!parsed.count(k)) unknown.insert(k);
  }
  EXPECT_TRUE(undocumented.empty()) << "keys the parser accepts but docs/scenario.md does not name: " << joined(undocumented);
  EXPECT_TRUE(unknown.empty()) << "keys docs/scenario.md names but the parser does not accept: " << joined(unknown);
}

}  // namespace
}  // namespace skytrace
