// What rll refuses to do to the files around it (docs/safety.md): replace a FIFO, a device, a
// folder, a link or a read-only file with an output; read a FIFO, a device or a folder as an
// input; use one file as both an input and an output; find an output location unusable only
// after the work; and messages that speak of what the user gave. (Interrupted merges and
// references: test_interrupt.cpp.)
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "rll/core/image.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

const std::string kScene = "builtin:cornell-box";

bool is_named_pipe(const fs::path& p) {
  struct stat st {};
  return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

fs::path make_fifo(const TempDir& dir, const std::string& name) {
  const fs::path p = dir / name;
  EXPECT_EQ(::mkfifo(p.c_str(), 0600), 0) << p;
  return p;
}

// A clean failure (exit 1..127) within `seconds`, mentioning every one of `parts`.
void expect_refused(const std::vector<std::string>& args, std::initializer_list<std::string> parts,
                    int seconds = 30) {
  SCOPED_TRACE(args[0]);
  CommandResult r = run_rll(args, seconds);
  EXPECT_GE(r.exit_code, 1) << r.output;
  EXPECT_LT(r.exit_code, 128) << r.output;
  expect_mentions(r.output, parts);
}

// A share of a tiny render split in `tasks`.
fs::path render_share(const TempDir& dir, int index, int tasks, const std::string& res = "8x8") {
  const fs::path p = dir / fmt::format("share{}.exr", index);
  CommandResult r =
      run_rll({"render", kScene, "--res", res, "--spp", "1", "--integrator", "direct", "--quiet",
               "--task", fmt::format("{}/{}", index, tasks), "-o", p.string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return p;
}

}  // namespace

TEST(SafetyCli, NoOutputReplacesAFifo) {
  TempDir dir;
  const fs::path share = render_share(dir, 0, 2);
  const std::string exr = make_fifo(dir, "out.exr").string(),
                    json = make_fifo(dir, "s.json").string();
  const std::string state = make_fifo(dir, "state.bin").string();
  fs::create_directories(dir / "cmp");
  const std::string summary = make_fifo(dir, "cmp/summary.json").string();
  const std::string r8 = "8x8";
  const std::vector<std::vector<std::string>> commands = {
      {"render", kScene, "--res", r8, "--spp", "1", "--quiet", "-o", exr},
      {"render", kScene, "--res", r8, "--spp", "1", "--quiet", "-o", (dir / "a.exr").string(),
       "--stats", json},
      {"render", kScene, "--res", r8, "--spp", "1", "--quiet", "-o", (dir / "b.exr").string(),
       "--sampler", "rll", "--rll-state", state, "--rll-state-mode", "save"},
      {"reference", kScene, "--res", r8, "--spp", "2", "--quiet", "--cache-dir",
       (dir / "cache").string(), "-o", exr},
      {"compare", kScene, "--samplers", "power", "--spp", "1", "--res", r8, "--reference-spp", "2",
       "--quiet", "--cache-dir", (dir / "cache").string(), "--out", (dir / "cmp").string()},
      {"merge", exr, share.string(), "--allow-missing"},
      {"convert", kScene, json},
  };
  for (const auto& args : commands) expect_refused(args, {"FIFO"});
  for (const auto& p : {exr, json, state, summary})
    EXPECT_TRUE(is_named_pipe(p)) << p << " was replaced";
  EXPECT_FALSE(fs::exists(dir / "a.exr")) << "the check must come before the render";
}

TEST(SafetyCli, ReadOnlyOutputsAreRefusedAndLinksWrittenThrough) {
  TempDir dir;
  const auto read_only = fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read;
  const fs::path ro = dir.write("ro.png", "keep"), ro_state = dir.write("ro.state", "keep");
  fs::permissions(ro, read_only);
  fs::permissions(ro_state, read_only);
  // Root may write a 0444 file: rll goes by the permission bits.
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "-o", ro.string()},
                 {"ro.png", "read-only"});
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "-o",
                  (dir / "x.png").string(), "--rll-state", ro_state.string()},
                 {"--rll-state", "ro.state", "read-only"});
  EXPECT_EQ(read_text(ro), "keep");
  EXPECT_EQ(read_text(ro_state), "keep");

  // A link is written through to its target, which the render replaces; the link stays.
  fs::create_directories(dir / "real");
  const fs::path target = dir.write("real/img.exr", "old");
  fs::create_symlink(fs::path("real") / "img.exr", dir / "link.exr");
  CommandResult r = run_rll({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "-o",
                             (dir / "link.exr").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(dir / "link.exr"));
  EXPECT_EQ(read_image(target).width(), 8);
}

TEST(SafetyCli, InputsThatAreNotFilesAreRefusedWithoutHanging) {
  TempDir dir;
  const std::string scene = make_fifo(dir, "scene.obj").string();
  const std::string state = make_fifo(dir, "state.bin").string();
  // An OBJ whose material library is a FIFO.
  const fs::path obj = dir.write("lit.obj", "mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  make_fifo(dir, "lib.mtl");
  const std::string out = (dir / "x.png").string();
  expect_refused({"render", scene, "--quiet", "-o", out}, {"scene.obj", "FIFO"});
  expect_refused({"render", obj.string(), "--quiet", "-o", out}, {"lib.mtl", "FIFO"});
  expect_refused({"reference", scene, "--quiet", "--cache-dir", (dir / "c").string()},
                 {"scene.obj", "FIFO"});
  expect_refused({"compare", scene, "--samplers", "power", "--spp", "1", "--quiet", "--out",
                  (dir / "cmp").string()},
                 {"scene.obj", "FIFO"});
  expect_refused({"convert", scene, (dir / "c.json").string()}, {"scene.obj", "FIFO"});
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "--sampler", "rll",
                  "--rll-state", state, "--rll-state-mode", "load", "-o", out},
                 {"--rll-state", "state.bin", "FIFO"});
  // A folder where a file is expected is named, never "basic_filebuf::underflow".
  fs::create_directories(dir / "folder.obj");
  fs::create_directories(dir / "state.d");
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"render", (dir / "folder.obj").string(), "--quiet", "-o", out},
           {"convert", (dir / "folder.obj").string(), (dir / "c.json").string()}}) {
    CommandResult r = run_rll(args, 30);
    expect_mentions(r.output, {"folder.obj", "folder"});
    EXPECT_EQ(r.output.find("basic_filebuf"), std::string::npos) << r.output;
  }
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "--sampler", "rll",
                  "--rll-state", (dir / "state.d").string(), "-o", out},
                 {"--rll-state", "state.d", "folder"});
}

TEST(SafetyCli, NoFileIsBothAnInputAndAnOutput) {
  TempDir dir;
  const fs::path s0 = render_share(dir, 0, 2), s1 = render_share(dir, 1, 2);
  // A merge written over the image it is checked against would "match it to 0".
  ASSERT_EQ(run_rll({"merge", (dir / "ref.exr").string(), s0.string(), s1.string()}).exit_code, 0);
  const std::string before = read_text(dir / "ref.exr");
  expect_refused({"merge", (dir / "ref.exr").string(), s0.string(), s1.string(), "--check-against",
                  (dir / "ref.exr").string()},
                 {"ref.exr", "input"});
  // By another spelling, and through a link.
  fs::create_symlink(dir / "ref.exr", dir / "ref-link.exr");
  expect_refused({"merge", (dir / "ref-link.exr").string(), s0.string(), s1.string(),
                  "--check-against", (dir.path() / "." / "ref.exr").string()},
                 {"ref-link.exr", "input"});
  fs::create_symlink(s0, dir / "s0-link.exr");
  expect_refused({"merge", (dir / "s0-link.exr").string(), s0.string(), s1.string()},
                 {"s0-link.exr", "input"});
  EXPECT_EQ(read_text(dir / "ref.exr"), before);

  // `reference -o` into the cache's own folder would overwrite its entries.
  const fs::path cache = dir / "cache";
  CommandResult r = run_rll({"reference", kScene, "--res", "8x8", "--spp", "2", "--quiet",
                             "--cache-dir", cache.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string entry;
  for (const auto& e : fs::directory_iterator(cache))
    if (e.path().string().ends_with(".half.exr")) entry = e.path().string();
  ASSERT_FALSE(entry.empty());
  const std::string half = read_text(entry);
  expect_refused({"reference", kScene, "--res", "8x8", "--spp", "2", "--quiet", "--cache-dir",
                  cache.string(), "-o", entry},
                 {"-o", "cache"});
  EXPECT_EQ(read_text(entry), half);

  // Two outputs of one render that are one file (here through a link whose name has the
  // target's extension: a link to another kind of file is refused before, as such).
  fs::create_symlink(dir / "img.exr", dir / "state.exr");
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "--sampler", "rll",
                  "-o", (dir / "img.exr").string(), "--rll-state", (dir / "state.exr").string()},
                 {"--rll-state", "-o", "same file"});
  // --rll-state by another spelling of --stats.
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "--sampler", "rll",
                  "-o", (dir / "x.exr").string(), "--stats", (dir / "s.json").string(),
                  "--rll-state", (dir.path() / "." / "s.json").string()},
                 {"--rll-state", "--stats", "same file"});
}

TEST(SafetyCli, TheCacheSidecarIsCheckedAgainstItsImage) {
  TempDir dir;
  const fs::path cache = dir / "cache";
  auto reference = [&](const std::string& spp) {
    return run_rll({"reference", kScene, "--res", "8x8", "--spp", spp, "--quiet", "--cache-dir",
                    cache.string()},
                   60);
  };
  ASSERT_EQ(reference("4").exit_code, 0);
  fs::path json;
  for (const auto& e : fs::directory_iterator(cache))
    if (e.path().extension() == ".json") json = e.path();
  ASSERT_FALSE(json.empty());
  // A 4-spp entry whose sidecar claims 4096 is not reused as a 4096-spp reference.
  nlohmann::json j = nlohmann::json::parse(read_text(json));
  j["spp"] = 4096;
  dir.write(fs::relative(json, dir.path()).string(), j.dump());
  CommandResult r = reference("8");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_mentions(r.output, {"damaged", "4 spp", "4096"});
  EXPECT_EQ(r.output.find("reused"), std::string::npos) << r.output;

  // A sidecar that is a folder is reported by name, deleted with its entry, and rendered again.
  fs::path json8;
  for (const auto& e : fs::directory_iterator(cache))
    if (e.path().extension() == ".json") json8 = e.path();
  ASSERT_FALSE(json8.empty());
  fs::remove(json8);
  fs::create_directories(json8 / "x");
  r = reference("8");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_mentions(r.output, {json8.filename().string(), "folder", "damaged"});
  r = reference("8");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_mentions(r.output, {"reused"});
}

TEST(SafetyCli, OutputLocationsAreCheckedBeforeTheWork) {
  TempDir dir;
  // A name too long for the folder is found before a render that would run a minute.
  const std::string long_name = (dir / (std::string(250, 'x') + ".exr")).string();
  double wall = 0;
  CommandResult r = run_rll(
      {"render", kScene, "--res", "32x32", "--time", "60", "--quiet", "-o", long_name}, 90, &wall);
  EXPECT_GE(r.exit_code, 1);
  EXPECT_LT(r.exit_code, 128);
  expect_mentions(r.output, {"-o", "file name", "bytes"});
  EXPECT_LT(wall, 20) << "the name was found too long only after rendering";
  r = run_rll({"reference", kScene, "--res", "32x32", "--spp", "100000000", "--quiet",
               "--cache-dir", (dir / "c").string(), "-o", long_name},
              90, &wall);
  expect_mentions(r.output, {"-o", "file name"});
  EXPECT_LT(wall, 20);

  // Too many frames, and frame names that sort.
  expect_refused({"render", kScene, "--res", "8x8", "--spp", "1", "--frames", "100001", "--quiet",
                  "-o", (dir / "f.png").string()},
                 {"--frames", "100000"});

  // Temporaries that a killed rll left beside an output are cleaned when it is written.
  const fs::path stale = dir.write("img.exr.tmp-2147483646-0", "stale");
  const fs::path other = dir.write("keep.exr.tmp-2147483646-0", "another output's");
  r = run_rll({"render", kScene, "--res", "8x8", "--spp", "1", "--quiet", "-o",
               (dir / "img.exr").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(other));
}

TEST(SafetyCli, MessagesSpeakOfWhatTheUserGave) {
  TempDir dir;
  const fs::path s2 = render_share(dir, 2, 4);
  // Which shares are missing, by number and by the --task that renders each.
  CommandResult r = run_rll({"merge", (dir / "m.exr").string(), s2.string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  expect_mentions(r.output,
                  {"3 of the 4 shares are missing", "shares 0, 1, 3", "--task 0/4", "--task 3/4"});
  // A sampler's parameter given in --samplers is reported there, not as --set.
  r = run_rll({"compare", kScene, "--samplers", "ltc:foo=1", "--spp", "1", "--res", "8x8",
               "--quiet", "--out", (dir / "cmp").string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  expect_mentions(r.output, {"--samplers", "ltc:foo", "'foo'"});
  EXPECT_EQ(r.output.find("--set"), std::string::npos) << r.output;
  r = run_rll({"render", kScene, "--sampler", "ltc:foo=1", "--res", "8x8", "--quiet", "-o",
               (dir / "x.png").string()});
  expect_mentions(r.output, {"--sampler", "ltc:foo"});
  EXPECT_EQ(r.output.find("--set"), std::string::npos) << r.output;
  // A reference of another size: the sizes, not "differs by up to inf".
  const fs::path s0 = render_share(dir, 0, 1);
  write_image(dir / "big.exr", Image(16, 12, Rgb(1)));
  r = run_rll({"merge", (dir / "m.exr").string(), s0.string(), "--check-against",
               (dir / "big.exr").string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  expect_mentions(r.output, {"16x12", "8x8", "big.exr"});
  EXPECT_EQ(r.output.find("differs"), std::string::npos) << r.output;
}
