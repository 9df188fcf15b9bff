// `rll error IMAGE REFERENCE`: the errors of an image against a reference (relMSE, trimmed
// relMSE, MRSE, MSE), as `rll compare` measures them, for images made by other commands (a
// merged render, another renderer's output).
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/eval/metrics.h"

namespace rll::cli {

namespace {

struct ErrorOptions {
  std::string image, reference, variance;
  bool json = false;
};

void run(const ErrorOptions& o) {
  const Image image = read_measured_image(o.image, MeasuredRole::image),
              reference = read_measured_image(o.reference, MeasuredRole::reference);
  if (image.width() != reference.width() || image.height() != reference.height())
    fail("error: '{}' is {}x{} and the reference '{}' is {}x{}", o.image, image.width(),
         image.height(), o.reference, reference.width(), reference.height());
  Image variance;
  if (!o.variance.empty()) {
    variance = read_measured_image(o.variance, MeasuredRole::reference_variance);
    if (variance.width() != reference.width() || variance.height() != reference.height())
      fail("error: --reference-variance '{}' is {}x{}, the reference {}x{}", o.variance,
           variance.width(), variance.height(), reference.width(), reference.height());
  }
  const ErrorMetrics m = error_metrics(image, reference, o.variance.empty() ? nullptr : &variance);
  if (o.json) {
    nlohmann::json j;
    for (const char* name : kMetricNames) j[name] = metric_by_name(m, name);
    j["reference_noise_subtracted"] = !o.variance.empty();
    fmt::print("{}\n", j.dump());
    return;
  }
  for (const char* name : kMetricNames)
    fmt::print("{:<15} {:.6g}\n", metric_label(name), metric_by_name(m, name));
  if (o.variance.empty())
    fmt::print(stderr, "rll: the reference's own noise is included (give --reference-variance "
                       "to subtract it)\n");
}

}  // namespace

void add_error_command(CLI::App& app) {
  auto o = std::make_shared<ErrorOptions>();
  auto* cmd = app.add_subcommand(
      "error", "Errors of an image against a reference: relMSE, trimmed relMSE, MRSE, MSE");
  cmd->add_option("image", o->image, "The image to measure (.exr, or any image rll reads)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("reference", o->reference, "The reference image, same size")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--reference-variance", o->variance,
                  "The reference's per-pixel variance (REF.variance.exr, written by rll "
                  "reference -o REF.exr): subtracted from every squared error, as compare does")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", o->json, "Print the metrics as one JSON object");
  cmd->callback([o] { run(*o); });
}

}  // namespace rll::cli
