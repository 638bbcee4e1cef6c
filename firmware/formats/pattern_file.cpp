#include "firmware/formats/pattern_file.hpp"

#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/file_storage.hpp"

namespace stria::firmware {

Result<pipeline::StripePattern> parsePattern(const std::string& text, const std::string& sourceName)
{
    const std::string where = "pattern '" + sourceName + "': ";
    cv::FileStorage fs;
    if (Status s = openFileStorage(fs, text, sourceName); !s) return s.withContext("pattern: ");
    const auto width = readInt(fs.root(), "stripe_width");
    if (!width) return width.status().withContext(where);
    const auto colors = readString(fs.root(), "colors");
    if (!colors) return colors.status().withContext(where);
    int window = 0;
    if (!fs["window"].empty()) {
        const auto w = readInt(fs.root(), "window");
        if (!w) return w.status().withContext(where);
        window = *w;
    }
    auto pattern = pipeline::StripePattern::create(*width, *colors, window);
    if (!pattern) return pattern.status().withContext(where);
    return pattern;
}

Result<pipeline::StripePattern> loadPatternFile(const std::string& path)
{
    const auto text = readTextFile(path);
    if (!text) return text.status().withContext("pattern: ");
    return parsePattern(*text, path);
}

Status savePatternFile(const pipeline::StripePattern& pattern, const std::string& path)
{
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    fs.writeComment("stria stripe pattern: stripe i covers projector columns [i*w-0.5, (i+1)*w-0.5)");
    fs << "stripe_width" << pattern.stripeWidth();
    fs << "window" << pattern.window();
    fs << "stripes" << pattern.stripeCount();
    fs << "colors" << pattern.colorLetters();
    return writeFileAtomically(path, fs.releaseAndGetString());
}

}  // namespace stria::firmware
