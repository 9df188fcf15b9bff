// Every relative link of the documentation (README.md, docs/*.md, bench/RESULTS.md) resolves: the
// file or folder it names exists inside the repository, and an #anchor names a heading of the
// Markdown file it points into, by GitHub's rules for heading anchors. The README is the front
// door and the manual lives in docs/, so a section moved or renamed must not leave a dead link.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace {

namespace fs = std::filesystem;

// The next code point of UTF-8 text at `i` (advancing it); a stray byte reads as itself.
char32_t next_code_point(const std::string& s, size_t& i) {
  const unsigned char c = s[i++];
  const int extra = c >= 0xF0 ? 3 : c >= 0xE0 ? 2 : c >= 0xC0 ? 1 : 0;
  char32_t cp = extra == 3 ? c & 0x07 : extra == 2 ? c & 0x0F : extra == 1 ? c & 0x1F : c;
  for (int k = 0; k < extra && i < s.size(); ++k) cp = (cp << 6) | (s[i++] & 0x3F);
  return cp;
}

void append_utf8(std::string& out, char32_t cp) {
  if (cp < 0x80) {
    out += char(cp);
  } else if (cp < 0x800) {
    out += char(0xC0 | (cp >> 6));
    out += char(0x80 | (cp & 0x3F));
  } else {
    out += char(0xE0 | (cp >> 12));
    out += char(0x80 | ((cp >> 6) & 0x3F));
    out += char(0x80 | (cp & 0x3F));
  }
}

// Letters outside ASCII that the docs could hold in a heading (Latin, Greek, Cyrillic); GitHub
// keeps every letter and drops symbols and punctuation (arrows, dashes, section signs).
bool is_non_ascii_letter(char32_t cp) {
  return (cp >= 0xC0 && cp <= 0x24F && cp != 0xD7 && cp != 0xF7) || (cp >= 0x370 && cp <= 0x4FF);
}

// A heading's anchor as GitHub makes it (github-slugger): the text as rendered (a link's target
// and inline code's backticks gone), lower case, every character but letters, digits, spaces,
// '-' and '_' removed, each space turned into '-'. "Parameters (`--set rll.NAME=VALUE`)" is
// #parameters---set-rllnamevalue.
std::string slug(const std::string& heading) {
  const std::string text =
      std::regex_replace(heading, std::regex(R"(!?\[([^\]]*)\]\([^)]*\))"), "$1");
  std::string out;
  for (size_t i = 0; i < text.size();) {
    char32_t cp = next_code_point(text, i);
    if (cp >= 'A' && cp <= 'Z') cp += 'a' - 'A';
    if (cp >= 0xC0 && cp <= 0xDE && cp != 0xD7) cp += 0x20;
    if (cp == ' ')
      out += '-';
    else if ((cp >= 'a' && cp <= 'z') || (cp >= '0' && cp <= '9') || cp == '-' || cp == '_' ||
             is_non_ascii_letter(cp))
      append_utf8(out, cp);
  }
  return out;
}

// Inline code spans blanked out, so that a link written as code (`[a](b)`) is not a link.
std::string without_code_spans(const std::string& line) {
  std::string out = line;
  for (size_t i = 0; i < out.size();) {
    if (out[i] != '`') {
      ++i;
      continue;
    }
    size_t run = out.find_first_not_of('`', i);
    if (run == std::string::npos) break;
    const std::string fence(run - i, '`');
    const size_t close = out.find(fence, run);
    if (close == std::string::npos) {
      i = run;
      continue;
    }
    for (size_t k = i; k < close + fence.size(); ++k) out[k] = ' ';
    i = close + fence.size();
  }
  return out;
}

struct Link {
  int line = 0;
  std::string target;  // as written: path, optionally #anchor
};

struct MarkdownFile {
  std::set<std::string> anchors;
  std::vector<Link> links;
};

// The headings' anchors and the links of a Markdown file, fenced code blocks left out.
MarkdownFile parse_markdown(const fs::path& file) {
  MarkdownFile md;
  std::ifstream in(file);
  std::map<std::string, int> seen;  // a repeated heading's anchor gets -1, -2, ...
  const std::regex heading(R"(^ {0,3}#{1,6}[ \t]+(.*?)[ \t]*#*[ \t]*$)");
  const std::regex fence(R"(^ {0,3}(```|~~~))");
  const std::regex inline_link(R"(\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\))");
  const std::regex definition(R"(^ {0,3}\[[^\]]+\]:\s*<?([^\s>]+)>?)");
  const std::regex html_anchor(R"re(<a\s+(?:name|id)="([^"]+)")re");
  bool in_fence = false;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (std::regex_search(line, fence)) {
      in_fence = !in_fence;
      continue;
    }
    if (in_fence) continue;
    std::smatch m;
    if (std::regex_match(line, m, heading)) {
      const std::string base = slug(m[1]);
      const int n = seen[base]++;
      md.anchors.insert(n == 0 ? base : base + "-" + std::to_string(n));
    }
    const std::string text = without_code_spans(line);
    for (std::sregex_iterator it(text.begin(), text.end(), html_anchor), end; it != end; ++it)
      md.anchors.insert((*it)[1]);
    for (std::sregex_iterator it(text.begin(), text.end(), inline_link), end; it != end; ++it)
      md.links.push_back({number, (*it)[1]});
    if (std::regex_search(text, m, definition)) md.links.push_back({number, m[1]});
  }
  return md;
}

std::string percent_decoded(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(s[i + 1]) && std::isxdigit(s[i + 2])) {
      out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// Every link of `files` (Markdown files under `root`) that does not resolve, one line each:
// "FILE:LINE: TARGET: why". Links with a scheme (https:, mailto:) are left to the web.
std::vector<std::string> broken_links(const fs::path& root, const std::vector<fs::path>& files,
                                      size_t* links_checked = nullptr) {
  const fs::path top = fs::weakly_canonical(root);
  std::map<fs::path, MarkdownFile> parsed;
  const auto markdown = [&](const fs::path& p) -> const MarkdownFile& {
    auto it = parsed.find(p);
    if (it == parsed.end()) it = parsed.emplace(p, parse_markdown(p)).first;
    return it->second;
  };
  const std::regex scheme(R"(^[A-Za-z][A-Za-z0-9+.-]*:)");
  std::vector<std::string> broken;
  size_t checked = 0;
  for (const fs::path& file : files) {
    const fs::path source = fs::weakly_canonical(file);
    for (const Link& link : markdown(source).links) {
      if (std::regex_search(link.target, scheme)) continue;
      ++checked;
      const size_t hash = link.target.find('#');
      const std::string path = percent_decoded(link.target.substr(0, hash));
      const std::string anchor = hash == std::string::npos ? "" : link.target.substr(hash + 1);
      const fs::path target =
          path.empty() ? source
                       : fs::weakly_canonical(path[0] == '/' ? top / path.substr(1)
                                                             : source.parent_path() / path);
      const auto report = [&](const std::string& why) {
        broken.push_back(fs::relative(source, top).string() + ":" + std::to_string(link.line) +
                         ": " + link.target + ": " + why);
      };
      const std::string rel = fs::relative(target, top).string();
      if (rel.empty() || rel.rfind("..", 0) == 0)
        report("outside the repository");
      else if (!fs::exists(target))
        report("no such file");
      else if (!anchor.empty() && target.extension() == ".md" &&
               markdown(target).anchors.count(anchor) == 0)
        report("no heading with this anchor in " + rel);
    }
  }
  if (links_checked) *links_checked = checked;
  return broken;
}

std::string joined(const std::vector<std::string>& lines) {
  std::ostringstream out;
  for (const auto& l : lines) out << l << "\n";
  return out.str();
}

TEST(DocLinks, AnchorsFollowGitHubsSlugs) {
  EXPECT_EQ(slug("`rll render`"), "rll-render");
  EXPECT_EQ(slug("Parameters (`--set rll.NAME=VALUE`)"), "parameters---set-rllnamevalue");
  EXPECT_EQ(slug("glTF 2.0"), "gltf-20");
  EXPECT_EQ(slug("MTL → rll material"), "mtl--rll-material");
  EXPECT_EQ(slug("Resampling on top of rll (`--set nee.candidates=M`, docs/nee.md)"),
            "resampling-on-top-of-rll---set-neecandidatesm-docsneemd");
  EXPECT_EQ(slug("RLL's end of pass on the device"), "rlls-end-of-pass-on-the-device");
  EXPECT_EQ(slug("See [the tree](x.md#tree): Éclairage"), "see-the-tree-éclairage");
  EXPECT_EQ(slug("Learning that keeps sharpening (`forget=changes`)"),
            "learning-that-keeps-sharpening-forgetchanges");
}

// The checker itself finds what it is for: a missing file, a missing anchor in another file and
// in the same one, a path out of the repository; and passes what resolves, a repeated heading's
// second anchor, links in code left alone.
TEST(DocLinks, FindsEveryKindOfBrokenLink) {
  rll::test::TempDir dir;
  fs::create_directories(dir.path() / "docs" / "images");
  dir.write("docs/images/a.png", "");
  dir.write("docs/b.md", "# B\n\n## Same\n\ntext\n\n## Same\n\n### `code` & more\n");
  const fs::path a =
      dir.write("docs/a.md",
                "# A\n\n"
                "[ok](b.md) [ok](b.md#same-1) [ok](b.md#code--more) ![ok](images/a.png)\n"
                "[ok](#a) [ok](../docs/b.md#b \"title\") [ok](https://example.com/x.md#nope)\n"
                "[ok](/docs/b.md#same) [ok](images/)\n"
                "`[not a link](missing.md)`\n"
                "```sh\n[not a link](missing.md)\n```\n"
                "[bad](missing.md)\n"
                "[bad](b.md#same-2)\n"
                "[bad](#nowhere)\n"
                "[bad](../../outside.md)\n"
                "[bad]: images/b.png\n");
  size_t checked = 0;
  const std::vector<std::string> broken = broken_links(dir.path(), {a}, &checked);
  EXPECT_EQ(checked, 13u);
  const std::vector<std::string> expected = {
      "docs/a.md:10: missing.md: no such file",
      "docs/a.md:11: b.md#same-2: no heading with this anchor in docs/b.md",
      "docs/a.md:12: #nowhere: no heading with this anchor in docs/a.md",
      "docs/a.md:13: ../../outside.md: outside the repository",
      "docs/a.md:14: images/b.png: no such file"};
  EXPECT_EQ(broken, expected) << joined(broken);
}

TEST(DocLinks, EveryLinkOfTheDocumentationResolves) {
  const fs::path root = RLL_SOURCE_DIR;
  std::vector<fs::path> files = {root / "README.md", root / "bench" / "RESULTS.md"};
  for (const auto& entry : fs::directory_iterator(root / "docs"))
    if (entry.path().extension() == ".md") files.push_back(entry.path());
  ASSERT_GE(files.size(), 10u);
  size_t checked = 0;
  const std::vector<std::string> broken = broken_links(root, files, &checked);
  EXPECT_TRUE(broken.empty()) << joined(broken);
  // The README is the front door: it links the manual rather than naming it.
  EXPECT_GE(checked, 40u);
}

}  // namespace
