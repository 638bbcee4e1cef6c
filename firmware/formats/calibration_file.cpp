#include "firmware/formats/calibration_file.hpp"

#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/file_storage.hpp"

namespace stria::firmware {
namespace {

Status readLens(const cv::FileNode& root, const std::string& prefix, pipeline::LensModel& lens)
{
    const auto width = readInt(root, (prefix + "_width").c_str());
    if (!width) return width.status();
    const auto height = readInt(root, (prefix + "_height").c_str());
    if (!height) return height.status();
    const auto K = readMatrix(root, (prefix + "_matrix").c_str(), 3, 3);
    if (!K) return K.status();
    const auto dist = readMatrix(root, (prefix + "_distortion").c_str(), 1, 5);
    if (!dist) return dist.status();
    lens.width = *width;
    lens.height = *height;
    lens.K = cv::Matx33d(K->data());
    lens.distortion = cv::Vec<double, 5>(dist->data());
    return Status::ok();
}

cv::Mat asMat(const cv::Matx33d& m) { return cv::Mat(m); }

}  // namespace

Result<pipeline::RigModel> parseCalibration(const std::string& text, const std::string& sourceName)
{
    const std::string where = "calibration '" + sourceName + "': ";
    cv::FileStorage fs;
    if (Status s = openFileStorage(fs, text, sourceName); !s) return s.withContext("calibration: ");
    pipeline::LensModel camera, projector;
    if (Status s = readLens(fs.root(), "camera", camera); !s) return s.withContext(where);
    if (Status s = readLens(fs.root(), "projector", projector); !s) return s.withContext(where);
    const auto R = readMatrix(fs.root(), "R", 3, 3);
    if (!R) return R.status().withContext(where);
    const auto T = readMatrix(fs.root(), "T", 3, 1);
    if (!T) return T.status().withContext(where);
    auto rig = pipeline::RigModel::create(camera, projector, cv::Matx33d(R->data()), cv::Vec3d(T->data()));
    if (!rig) return rig.status().withContext(where);
    return rig;
}

Result<pipeline::RigModel> loadCalibrationFile(const std::string& path)
{
    const auto text = readTextFile(path);
    if (!text) return text.status().withContext("calibration: ");
    return parseCalibration(*text, path);
}

Status saveCalibrationFile(const pipeline::RigModel& rig, const std::string& path)
{
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    fs.writeComment("stria rig calibration: X_projector = R * X_camera + T, millimetres");
    fs << "camera_width" << rig.camera().width << "camera_height" << rig.camera().height;
    fs << "camera_matrix" << asMat(rig.camera().K);
    fs << "camera_distortion" << cv::Mat(rig.camera().distortion).reshape(1, 1);
    fs << "projector_width" << rig.projector().width << "projector_height" << rig.projector().height;
    fs << "projector_matrix" << asMat(rig.projector().K);
    fs << "projector_distortion" << cv::Mat(rig.projector().distortion).reshape(1, 1);
    fs << "R" << asMat(rig.R());
    fs << "T" << cv::Mat(rig.T());
    return writeFileAtomically(path, fs.releaseAndGetString());
}

}  // namespace stria::firmware
