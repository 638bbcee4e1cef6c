#include "firmware/formats/file_storage.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace stria::firmware {

Result<std::string> readTextFile(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status::error("cannot read '" + path + "': " + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) return Status::error("cannot read '" + path + "': " + std::strerror(errno));
    return text.str();
}

Status openFileStorage(cv::FileStorage& fs, const std::string& text, const std::string& sourceName)
{
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
        return Status::error("'" + sourceName + "' is empty");
    try {
        std::string source = text;
        // FileStorage wants the YAML directive; files written by hand often lack it.
        if (source.rfind("%YAML", 0) != 0 && source.front() != '<' && source.front() != '{')
            source = "%YAML:1.0\n---\n" + source;
        if (!fs.open(source, cv::FileStorage::READ | cv::FileStorage::MEMORY))
            return Status::error("'" + sourceName + "' is not a readable YAML, XML or JSON file");
    } catch (const cv::Exception& e) {
        return Status::error("'" + sourceName + "' is not valid YAML: " + e.msg);
    }
    return Status::ok();
}

std::string stripYamlComment(const std::string& value)
{
    std::size_t end = value.size();
    for (std::size_t i = 0; i < value.size(); ++i) {
        if (value[i] == '#' && (i == 0 || value[i - 1] == ' ' || value[i - 1] == '\t')) {
            end = i;
            break;
        }
    }
    while (end > 0 && (value[end - 1] == ' ' || value[end - 1] == '\t')) --end;
    return value.substr(0, end);
}

Result<int> readInt(const cv::FileNode& root, const char* key)
{
    const cv::FileNode n = root[key];
    if (n.empty() || n.isNone()) return Status::error(std::string("missing key '") + key + "'");
    if (!n.isInt()) {
        if (n.isReal() && std::floor(n.real()) == n.real()) return static_cast<int>(n.real());
        return Status::error(std::string("key '") + key + "' must be a whole number");
    }
    return static_cast<int>(n);
}

Result<std::string> readString(const cv::FileNode& root, const char* key)
{
    const cv::FileNode n = root[key];
    if (n.empty() || n.isNone()) return Status::error(std::string("missing key '") + key + "'");
    if (!n.isString()) return Status::error(std::string("key '") + key + "' must be a string");
    return stripYamlComment(n.string());
}

Result<std::vector<double>> readMatrix(const cv::FileNode& root, const char* key, int rows, int cols)
{
    const cv::FileNode n = root[key];
    const std::string shape = std::to_string(rows) + "x" + std::to_string(cols);
    if (n.empty() || n.isNone()) return Status::error(std::string("missing key '") + key + "' (" + shape + " matrix)");
    std::vector<double> values;
    try {
        if (n.isMap()) {
            cv::Mat m;
            n >> m;
            if (m.empty()) return Status::error(std::string("key '") + key + "' is not a matrix");
            if (m.total() * m.channels() != static_cast<std::size_t>(rows * cols))
                return Status::error(std::string("key '") + key + "' must be " + shape + ", found " +
                                     std::to_string(m.rows) + "x" + std::to_string(m.cols));
            cv::Mat d;
            m.reshape(1, 1).convertTo(d, CV_64F);
            values.assign(d.ptr<double>(), d.ptr<double>() + d.total());
        } else if (n.isSeq()) {
            for (const auto& item : n) {
                if (item.isSeq()) {
                    for (const auto& inner : item) values.push_back(static_cast<double>(inner));
                } else {
                    values.push_back(static_cast<double>(item));
                }
            }
            if (values.size() != static_cast<std::size_t>(rows * cols))
                return Status::error(std::string("key '") + key + "' must be " + shape + " (" +
                                     std::to_string(rows * cols) + " numbers), found " +
                                     std::to_string(values.size()) + " numbers");
        } else {
            return Status::error(std::string("key '") + key + "' must be a " + shape + " matrix");
        }
    } catch (const cv::Exception& e) {
        return Status::error(std::string("key '") + key + "' cannot be read: " + e.msg);
    }
    for (double v : values)
        if (!std::isfinite(v)) return Status::error(std::string("key '") + key + "' contains NaN or infinity");
    return values;
}

}  // namespace stria::firmware
