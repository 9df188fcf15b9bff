// A one-line progress bar on stderr (samples done, rate, time left), shown only on a terminal.
#pragma once

#include <string>

#include "rll/render/render.h"

namespace rll {

class ProgressBar {
 public:
  // `label` prefixes the line; the bar is silent when stderr is not a terminal or !enabled.
  ProgressBar(std::string label, bool enabled = true);
  ~ProgressBar();
  void update(const RenderProgress& p);
  void finish();

 private:
  std::string m_label;
  bool m_enabled;
  bool m_drawn = false;
};

// "1.2 s", "3 min 05 s"...
std::string format_duration(double seconds);

}  // namespace rll
