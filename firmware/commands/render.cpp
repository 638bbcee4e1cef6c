// stria render: render a simulator scene with its ground truth, and write the
// rig's calibration and pattern so `stria decode` can be run on the image.
#include "firmware/cli.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/image_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "hal/sim/scene/scene.hpp"

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace stria::firmware {
namespace {

using namespace stria::hal::sim;

constexpr const char* kUsage = R"(usage:
  stria render --scene NAME [--rig desktop|desktop-large|fingerprint|endoscope]
               [--albedo uniform|checker|coloured|photo] [--noise S] [--contrast C]
               [--ambient A] [--seed N] [--bayer] [--led-off] --out IMAGE.png
               [--depth DEPTH.tiff] [--columns COLUMNS.tiff]
               [--calib-out CALIB.yaml] [--pattern-out PATTERN.yaml]

Scenes: plane, sphere, relief, clutter, fan, fingertip, tube. The rig defaults
to the one the scene is made for (fingertip: fingerprint, tube: endoscope,
others: desktop); the albedo to the scene's own (relief: photo, others
uniform). --noise is the sigma of additive Gaussian noise in 8-bit digits,
--contrast the pattern contrast (0..1], --ambient the ambient light as a
fraction of projector white. --seed fixes the scene and the noise.
Writes the BGR image (PNG), the ground-truth depth (z in mm, NaN where no
surface) and the projector column lighting each pixel (NaN in shadow) as
32-bit float TIFFs, and the rig's calibration and pattern files.)";

int run(std::span<const std::string> argv);
const Command kRender{"render", "render a simulated scene with ground truth", kUsage, run};

struct NamedRig {
    const char* name;
    SimRig (*make)();
};
constexpr NamedRig kRigs[] = {
    {"desktop", desktopRig}, {"desktop-large", desktopRigLarge}, {"fingerprint", fingerprintRig}, {"endoscope", endoscopeRig}};

const char* defaultRigName(SceneKind kind)
{
    if (kind == SceneKind::Fingertip) return "fingerprint";
    if (kind == SceneKind::Tube) return "endoscope";
    return "desktop";
}

int run(std::span<const std::string> argv)
{
    Args args(argv,
              {"scene", "rig", "albedo", "noise", "contrast", "ambient", "seed", "out", "depth", "columns", "calib-out",
               "pattern-out"},
              {"bayer", "led-off"});
    if (!args.ok()) return usageError(kRender, args.error());
    if (!args.require({"scene", "out"})) return usageError(kRender, args.error());
    if (!args.positional().empty()) return usageError(kRender, "unexpected argument '" + args.positional()[0] + "'");

    const std::string sceneText = *args.value("scene");
    const auto kind = sceneFromName(sceneText);
    if (!kind)
        return usageError(kRender, "unknown scene '" + sceneText +
                                       "': known scenes are plane, sphere, relief, clutter, fan, fingertip, tube");
    const std::string rigText = args.valueOr("rig", defaultRigName(*kind));
    const NamedRig* named = nullptr;
    for (const NamedRig& r : kRigs)
        if (rigText == r.name) named = &r;
    if (!named)
        return usageError(kRender, "unknown rig '" + rigText + "': known rigs are desktop, desktop-large, fingerprint, endoscope");
    const std::string albedoText = args.valueOr("albedo", albedoName(defaultAlbedo(*kind)));
    const auto albedo = albedoFromName(albedoText);
    if (!albedo)
        return usageError(kRender, "unknown albedo '" + albedoText + "': known albedos are uniform, checker, coloured, photo");

    RenderSettings settings;
    settings.noiseSigma = args.number("noise", 0.0);
    settings.contrast = args.number("contrast", 1.0);
    settings.ambient = args.number("ambient", settings.ambient);
    const long seed = args.integer("seed", 1);
    if (!args.ok()) return usageError(kRender, args.error());
    if (!(settings.noiseSigma >= 0 && settings.noiseSigma <= 255)) return usageError(kRender, "--noise must be in [0, 255]");
    if (!(settings.contrast > 0 && settings.contrast <= 1)) return usageError(kRender, "--contrast must be in (0, 1]");
    if (!(settings.ambient >= 0 && settings.ambient <= 10)) return usageError(kRender, "--ambient must be in [0, 10]");
    if (seed < 0) return usageError(kRender, "--seed must be >= 0");
    settings.seed = static_cast<std::uint64_t>(seed);
    settings.bayer = args.has("bayer");
    settings.projectorOn = !args.has("led-off");

    const SimRig rig = named->make();
    const Scene scene = makeScene(*kind, rig, *albedo, settings.seed);
    const SceneRenderer renderer(rig);
    Rendering rendering;
    if (Status s = renderer.render(scene, settings, rendering); !s) return failure("render", s.message());

    // Write every requested file; if one fails, remove those already written
    // so that no partial set of outputs is left behind.
    std::vector<std::pair<std::string, std::function<Status(const std::string&)>>> outputs;
    outputs.emplace_back(*args.value("out"), [&](const std::string& p) { return writePng(p, rendering.image); });
    if (auto p = args.value("depth"))
        outputs.emplace_back(*p, [&](const std::string& q) { return writeTiffFloat(q, rendering.depth); });
    if (auto p = args.value("columns"))
        outputs.emplace_back(*p, [&](const std::string& q) { return writeTiffFloat(q, rendering.projectorColumn); });
    if (auto p = args.value("calib-out"))
        outputs.emplace_back(*p, [&](const std::string& q) { return saveCalibrationFile(rig.rig, q); });
    if (auto p = args.value("pattern-out"))
        outputs.emplace_back(*p, [&](const std::string& q) { return savePatternFile(rig.pattern, q); });
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        if (Status s = outputs[i].second(outputs[i].first); !s) {
            for (std::size_t j = 0; j < i; ++j) std::remove(outputs[j].first.c_str());
            return failure("render", s.message());
        }
    }
    const double litFraction = cv::countNonZero(rendering.lit) / static_cast<double>(rendering.lit.total());
    std::printf("wrote %s: scene %s, rig %s (%dx%d), albedo %s, noise %.1f, contrast %.2f, %s, %.0f%% lit, "
                "%d ideal edge crossings\n",
                outputs[0].first.c_str(), sceneName(*kind), named->name, rig.rig.camera().width,
                rig.rig.camera().height, albedoName(*albedo), settings.noiseSigma, settings.contrast,
                settings.projectorOn ? "LED on" : "LED off", 100 * litFraction,
                idealEdgeCrossings(rendering, rig.pattern));
    return kExitOk;
}

}  // namespace

STRIA_COMMAND(render, kRender);

}  // namespace stria::firmware
