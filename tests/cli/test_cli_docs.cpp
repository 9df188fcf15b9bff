// The command reference is whole: every flag that `rll COMMAND --help` lists is documented in that
// command's section of docs/cli.md, every command has a section there, and the README shows an
// example of each command. A flag added to a command without a line in the manual fails here.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

using namespace rll::test;

namespace {

// The subcommands that `rll --help` lists.
std::vector<std::string> commands() {
  const CommandResult r = run_rll({"--help"}, 60);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> names;
  std::istringstream in(r.output.substr(r.output.find("Subcommands:")));
  const std::regex row(R"(^  ([a-z]+) )");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, row)) names.push_back(m[1]);
  }
  return names;
}

// The long flags of `rll COMMAND --help` (of `rll --help` for an empty COMMAND), --help itself
// left out.
std::set<std::string> flags_of(const std::string& command) {
  const CommandResult r = run_rll(command.empty() ? std::vector<std::string>{"--help"}
                                                  : std::vector<std::string>{command, "--help"},
                                  60);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::set<std::string> flags;
  const std::regex option(R"(^  (?:-[a-zA-Z],)?(--[a-z][a-z0-9-]*))");
  std::istringstream in(r.output);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, option) && m[1] != "--help") flags.insert(m[1]);
  }
  return flags;
}

// The text of docs/cli.md's section "## `rll COMMAND`", up to the next section.
std::string section_of(const std::string& doc, const std::string& command) {
  const std::string heading = "\n## `rll " + command + "`";
  const size_t begin = doc.find(heading);
  if (begin == std::string::npos) return "";
  const size_t end = doc.find("\n## ", begin + heading.size());
  return doc.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

// Whether `text` names `flag` as code: a backtick, the flag, and then no further letter of a
// longer flag (`--reference` must not be found in `--reference-spp`).
bool documents(const std::string& text, const std::string& flag) {
  const std::string quoted = "`" + flag;
  for (size_t at = text.find(quoted); at != std::string::npos; at = text.find(quoted, at + 1)) {
    const size_t next = at + quoted.size();
    if (next == text.size() ||
        !(std::isalnum(static_cast<unsigned char>(text[next])) || text[next] == '-'))
      return true;
  }
  return false;
}

TEST(CliDocs, EveryFlagOfEveryCommandIsInDocsCli) {
  const std::string doc = read_text(std::filesystem::path(RLL_SOURCE_DIR) / "docs" / "cli.md");
  ASSERT_FALSE(doc.empty()) << "docs/cli.md";
  const std::vector<std::string> names = commands();
  ASSERT_GE(names.size(), 10u);
  size_t total = 0;
  for (const std::string& command : names) {
    const std::string section = section_of(doc, command);
    ASSERT_FALSE(section.empty()) << "docs/cli.md has no section \"## `rll " << command << "`\"";
    for (const std::string& flag : flags_of(command)) {
      ++total;
      EXPECT_TRUE(documents(section, flag)) << "`rll " << command << " " << flag
                                            << "` is not in docs/cli.md's section of " << command;
    }
  }
  EXPECT_GE(total, 80u);  // the parse found the flags (render alone has 24)
  // The program's own flags (--version) in the introduction, before the first command.
  const std::string intro = doc.substr(0, doc.find("\n## "));
  for (const std::string& flag : flags_of(""))
    EXPECT_TRUE(documents(intro, flag))
        << "`rll " << flag << "` is not in docs/cli.md's introduction";
}

TEST(CliDocs, TheReadmeShowsEveryCommand) {
  const std::string readme = read_text(std::filesystem::path(RLL_SOURCE_DIR) / "README.md");
  ASSERT_FALSE(readme.empty()) << "README.md";
  for (const std::string& command : commands())
    EXPECT_NE(readme.find("\nrll " + command), std::string::npos)
        << "README.md has no example line starting `rll " << command << "`";
}

TEST(CliDocs, FlagsAreMatchedWhole) {
  EXPECT_TRUE(documents("| `--reference FILE` |", "--reference"));
  EXPECT_TRUE(documents("`--reference`, `--json`", "--json"));
  EXPECT_FALSE(documents("| `--reference-spp N` |", "--reference"));
  EXPECT_FALSE(documents("--reference, without backticks", "--reference"));
}

}  // namespace
