#pragma once
// Pattern files: OpenCV FileStorage YAML.
//   stripe_width: 8            # projector pixels per stripe
//   colors: "CGMRGWBG..."      # stripe colours, left to right (K B G C R M Y W)
//   window: 4                  # optional: the window length that is unique
#include "pipeline/pattern.hpp"

#include <string>

namespace stria::firmware {

Result<pipeline::StripePattern> loadPatternFile(const std::string& path);
// Parses an in-memory YAML/XML/JSON text (FileStorage MEMORY mode).
Result<pipeline::StripePattern> parsePattern(const std::string& text, const std::string& sourceName);
Status savePatternFile(const pipeline::StripePattern& pattern, const std::string& path);

}  // namespace stria::firmware
