// `rll merge OUT.exr SHARE.exr...`: the shares of a render split by samples (`rll render
// --task I/N`) merged into the render they are parts of (src/rll/render/share.h).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/eval/metrics.h"
#include "rll/render/share.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

struct MergeOptions {
  std::string output;
  std::vector<std::string> inputs;
  std::string check_against;
  double tolerance = 1e-5;
  bool allow_missing = false;
};

void merge(const MergeOptions& o) {
  // Until the write begins a signal ends the merge at once: nothing was written.
  install_interrupt_handler();
  const fs::path output = o.output;
  prepare_output(output, "merge", {".exr"});
  std::vector<fs::path> inputs(o.inputs.begin(), o.inputs.end());
  // A merge written over the image it is checked against would match it "to 0".
  if (!o.check_against.empty()) inputs.emplace_back(o.check_against);
  refuse_input(output, "merge", inputs);
  inputs.resize(o.inputs.size());
  MergeResult m = merge_shares(inputs);
  if (!m.missing.empty() && !o.allow_missing)
    fail("merge: {} (a job failed?); render them, or merge what there is with --allow-missing",
         missing_shares_text(m.missing, m.info.tasks));
  for (const std::string& w : m.warnings) fmt::print(stderr, "rll: warning: {}\n", w);
  // From here a signal lets the write finish (its temporary is renamed or removed, never left).
  begin_work();
  write_exr(output, m.file);
  if (interrupted())
    throw Interrupted(fmt::format("interrupted while writing the merge; {} is complete", output.string()));
  fmt::print(stderr, "merged {} of {} shares into {}: {} spp{}\n", m.info.held.size(), m.info.tasks,
             output.string(), m.min_count,
             m.max_count != m.min_count ? fmt::format(" (up to {} in some pixels)", m.max_count) : "");
  if (!o.check_against.empty()) {
    const Image ref = read_measured_image(o.check_against, MeasuredRole::reference);
    if (ref.width() != m.file.image.width() || ref.height() != m.file.image.height())
      fail("merge --check-against {}: it is {}x{}, the merged image is {}x{}", o.check_against,
           ref.width(), ref.height(), m.file.image.width(), m.file.image.height());
    const double d = max_relative_difference(m.file.image, ref);
    if (!(d <= o.tolerance))
      fail("merge --check-against {}: the merged image differs from it by up to {:.3g} "
           "(relative), more than --tolerance {}",
           o.check_against, d, o.tolerance);
    fmt::print(stderr, "matches {} to {:.3g} (relative; tolerance {})\n", o.check_against, d,
               o.tolerance);
  }
}

}  // namespace

void add_merge_command(CLI::App& app) {
  auto o = std::make_shared<MergeOptions>();
  auto* cmd = app.add_subcommand(
      "merge",
      "Merge the shares of a render split by samples (rll render --task I/N, one .exr each) "
      "into the whole render: each pixel's mean weighted by its sample count");
  cmd->add_option("output", o->output, "merged image (.exr), never one of the inputs")->required();
  cmd->add_option("inputs", o->inputs,
                  "share images (.exr) written by rll render; all must come from one render "
                  "(same scene, resolution, integrator, sampler, --set, seed, frame and --spp), "
                  "each share once; merged images merge again")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_flag("--allow-missing", o->allow_missing,
                "Write the merge even if some shares of the render are missing (unbiased, "
                "with fewer samples)");
  cmd->add_option("--check-against", o->check_against,
                  "Compare the merged image with this one (the single render of all the "
                  "samples) and fail if any pixel differs by more than --tolerance (relative)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--tolerance", o->tolerance, "Largest relative difference --check-against accepts")
      ->capture_default_str()
      ->check(number_in(0, 1));
  cmd->callback([o] { merge(*o); });
}

}  // namespace rll::cli
