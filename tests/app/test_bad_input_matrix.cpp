// The bad-input matrix: every input vdmap reads, each way it can be bad, and the exact
// error class expected. One row is one test. Library readers must throw InputError with a one-line
// message; the command line must exit 1 with a one-line "vdmap VERB: error: ..." (or CLI11's usage
// error for unparsable options) and leave no output behind. The good input of every reader is
// checked too, so no row passes by accident.
//
// Side effect: each file-reading row's bad file and the good file are copied into the fuzzers'
// seed corpus (VDMAP_FUZZ_SEEDS/<target>/), so the fuzzers start from every known bad case.
#include <cstdio>
#include <functional>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/view/view_file.h"

#include "mapping/core/error.h"
#include "mapping/eval/trajectory_error.h"
#include "mapping/files/ply_reader.h"
#include "mapping/files/ply_writer.h"
#include "mapping/files/session_file.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/image_codec.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/sequence/sequence.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;
using test::readFile;
using test::writeText;

enum class Expect {
  kInputError,  ///< vdmap::InputError, message "FILE[:LINE]: ..."
  kCliError,    ///< `vdmap ...` exits 1 with one line "vdmap VERB: error: ..." (a value against files or data)
  kCliUsage,    ///< `vdmap ...` exits with CLI11's code (100-114) and one line ending "(see --help)": the
                ///< command line is wrong by itself (docs/cli.md "Exit codes and errors")
};

/// One input vdmap reads: how to make a good one in a folder, and how vdmap reads it. The command
/// line has no `read`: its bad cases return the arguments (with {dir} for the folder).
struct Input {
  const char* name;
  const char* path;         ///< the file read, relative to the folder ("" for the command line)
  const char* fuzz_target;  ///< seed corpus folder, or nullptr
  std::function<void(const fs::path& dir)> make_good;
  std::function<void(const fs::path& file)> read;
};

const std::string kMeshPly =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
    "property list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n";

// A binary little-endian mesh header for 3 vertices of float x y z, float r g b and one face.
std::string binaryMesh(const std::string& body) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nproperty float red\nproperty float green\nproperty float blue\nelement face 1\n"
         "property list uchar int vertex_indices\nend_header\n" +
         body;
}

std::string goodSession() {
  static const std::string bytes = [] {
    const Mapper mapper = test::mapTurningBoxRoom(2);
    return encodeSession(mapper.graph(), sessionInfo(mapper, {}));
  }();
  return bytes;
}

void setU32(std::string* bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) (*bytes)[at + i] = static_cast<char>(v >> (8 * i));
}

const std::vector<Input>& inputs() {
  static const std::vector<Input> all = {
      {"sequence", "seq", "tum_list", [](const fs::path& d) { test::writeTinySequence(d / "seq"); },
       [](const fs::path& f) { Sequence::open(f).load(0); }},
      {"trajectory", "poses.txt", "pose",
       [](const fs::path& d) { writeText(d / "poses.txt", "# t tx ty tz qx qy qz qw\n0.5 1 2 3 0 0 0 1\n"); },
       [](const fs::path& f) { readTumTrajectory(f); }},
      {"corrected_trajectory", "poses.txt", "pose",
       [](const fs::path& d) { writeText(d / "poses.txt", "0.0 1 2 3 0 0 0 1\n"); },
       [](const fs::path& f) {
         const Mapper mapper = test::mapTurningBoxRoom(1);  // one keyframe at t = 0
         KeyframeGraph graph = mapper.graph();
         applyTrajectoryFile(graph, f);
       }},
      {"trajectory_pair", "est.txt", "pose",
       [](const fs::path& d) {
         writeText(d / "est.txt", "0.0 1 2 3 0 0 0 1\n0.1 1 2 3.1 0 0 0 1\n0.2 1.1 2 3.2 0 0 0 1\n");
         writeText(d / "gt.txt", "0.005 1 2 3 0 0 0 1\n0.105 1 2 3.1 0 0 0 1\n0.205 1.1 2 3.2 0 0 0 1\n");
       },
       [](const fs::path& f) { evaluateTrajectoryFiles(f, f.parent_path() / "gt.txt"); }},
      {"camera_yaml", "camera.yaml", "camera",
       [](const fs::path& d) {
         writeText(d / "camera.yaml",
                   "fx: 500\nfy: 501\ncx: 320\ncy: 240\ndepth_scale: 1000\nwidth: 640\nheight: 480\n");
       },
       [](const fs::path& f) { readCameraFile(f); }},
      {"camera_json", "camera.json", "camera",
       [](const fs::path& d) { writeText(d / "camera.json", "{\"preset\": \"tum-fr1\", \"fx\": 517.3}"); },
       [](const fs::path& f) { readCameraFile(f); }},
      {"ply_mesh", "m.ply", "ply", [](const fs::path& d) { writeText(d / "m.ply", kMeshPly); },
       [](const fs::path& f) { readPlyMesh(f); }},
      {"ply_ellipsoids", "e.ply", "ply",
       [](const fs::path& d) {
         Ellipsoid e;
         e.mean = {1, 2, 3};
         e.cov = Eigen::Matrix3d::Identity() * 1e-4;
         e.count = 12;
         e.keyframe = 3;
         writeEllipsoidPly(d / "e.ply", {e, e});
       },
       [](const fs::path& f) { readPlyEllipsoids(f); }},
      {"session", "s.vdmap", "session", [](const fs::path& d) { writeText(d / "s.vdmap", goodSession()); },
       [](const fs::path& f) { loadSession(f); }},
      {"command_line", "", nullptr, [](const fs::path& d) { test::writeTinySequence(d / "seq"); }, nullptr},
  };
  return all;
}

/// One bad case. `damage` changes the good input in the folder (for the command line it returns
/// the arguments); `fragment` must appear in the message ({dir} is the folder there too).
struct BadCase {
  const char* input;
  const char* name;
  Expect expect;
  const char* fragment;
  std::function<std::string(const fs::path& dir)> damage;
};

std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

// Damages one file by replacing its text.
std::function<std::string(const fs::path&)> write(const char* file, std::string text) {
  return [file, text](const fs::path& d) {
    writeText(d / file, text);
    return std::string();
  };
}
// Damages one image by writing `pixels` in its place.
std::function<std::string(const fs::path&)> image(const char* file, cv::Mat pixels) {
  return [file, pixels](const fs::path& d) {
    test::writeImage((d / file), pixels);
    return std::string();
  };
}
// Damages one image by writing `pixels` encoded as `ext` (".jpg", ".png"), cut to `fraction` of
// its bytes, in its place (the decoder goes by the bytes, not the file name).
std::function<std::string(const fs::path&)> cutImage(const char* file, cv::Mat pixels, const char* ext,
                                                     double fraction) {
  return [=](const fs::path& d) {
    const std::string bytes =
        std::string(ext) == ".png" ? encodePng(pixels, ChannelOrder::kBgr) : encodeJpeg(pixels, 95, ChannelOrder::kBgr);
    writeText(d / file, bytes.substr(0, static_cast<std::size_t>(bytes.size() * fraction)));
    return std::string();
  };
}
// A textured 64x48 colour image, so that its JPEG has entropy-coded data to cut.
cv::Mat texture() {
  cv::Mat m(48, 64, CV_8UC3);
  cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(255));
  return m;
}
// Applies `damage`, then returns `arguments` (a command-line row on a damaged input).
std::function<std::string(const fs::path&)> then(std::function<std::string(const fs::path&)> damage,
                                                 std::string arguments) {
  return [=](const fs::path& d) {
    damage(d);
    return arguments;
  };
}
// Puts a folder where `file` is (a folder given as a file).
std::function<std::string(const fs::path&)> folderAt(const char* file) {
  return [file](const fs::path& d) {
    fs::remove_all(d / file);
    fs::create_directory(d / file);
    return std::string();
  };
}
std::function<std::string(const fs::path&)> removeFile(const char* file) {
  return [file](const fs::path& d) {
    fs::remove_all(d / file);
    return std::string();
  };
}
// Writes v.json, a good view file (writeViewFile of the default view) changed by `edit`.
std::function<std::string(const fs::path&)> viewFile(std::function<void(nlohmann::json&)> edit) {
  return [edit](const fs::path& d) {
    app::writeViewFile(d / "v.json", render::ViewSpec{}, GlobalMapParams{}, "s.vdmap");
    nlohmann::json j = nlohmann::json::parse(readFile(d / "v.json"));
    edit(j);
    writeText(d / "v.json", j.dump());
    return std::string();
  };
}
std::function<std::string(const fs::path&)> session(std::function<void(std::string*)> edit) {
  return [edit](const fs::path& d) {
    std::string bytes = goodSession();
    edit(&bytes);
    writeText(d / "s.vdmap", bytes);
    return std::string();
  };
}
// Maps frames `frames` of seq and saves the session as s.vdmap; then writes `other`, a copy of
// the tiny sequence with `frames_other` frames and timestamps `shift_s` later ("": none).
std::function<std::string(const fs::path&)> savedSession(std::string frames, std::string other, double shift_s = 0.0,
                                                         int frames_other = 3) {
  return [=](const fs::path& d) {
    const test::RunResult r = test::runVdmap("map '" + (d / "seq").string() + "' --frames " + frames + " --out '" +
                                             (d / "first").string() + "' --save '" + (d / "s.vdmap").string() + "'");
    if (r.exit_code != 0) throw std::runtime_error("the session to continue was not made: " + r.err);
    if (other.empty()) return std::string();
    test::writeTinySequence(d / other, frames_other);
    for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"}) {
      std::string text;
      std::istringstream lines(readFile(d / other / list));
      for (std::string line; std::getline(lines, line);) {
        double t = 0;
        char rest[256];
        if (line[0] != '#' && std::sscanf(line.c_str(), "%lf %255[^\n]", &t, rest) == 2) {
          char shifted[300];
          std::snprintf(shifted, sizeof shifted, "%.6f %s", t + shift_s, rest);
          text += std::string(shifted) + "\n";
        } else {
          text += line + "\n";
        }
      }
      writeText(d / other / list, text);
    }
    return std::string();
  };
}
std::function<std::string(const fs::path&)> args(std::string a) {
  return [a](const fs::path&) { return a; };
}

const std::vector<BadCase>& badCases() {
  using E = Expect;
  static const std::vector<BadCase> all = {
      // Sequence folders and their lists (TUM layout).
      {"sequence", "missing_folder", E::kInputError, "seq: no such sequence folder", removeFile("seq")},
      {"sequence", "folder_is_a_file", E::kInputError, "is neither a sequence folder nor a recording",
       [](const fs::path& d) {
         fs::remove_all(d / "seq");
         return write("seq", "x")(d);
       }},
      {"sequence", "missing_rgb_list", E::kInputError, "rgb.txt: cannot open", removeFile("seq/rgb.txt")},
      {"sequence", "missing_depth_list", E::kInputError, "depth.txt: cannot open", removeFile("seq/depth.txt")},
      {"sequence", "missing_groundtruth", E::kInputError, "groundtruth.txt: no such file; --poses gt needs",
       removeFile("seq/groundtruth.txt")},
      {"sequence", "extra_column", E::kInputError, "depth.txt:2: expected 'timestamp path', got 3",
       write("seq/depth.txt", "0.0 depth/000000.png\n0.0333 depth/000001.png extra\n")},
      {"sequence", "timestamp_not_a_number", E::kInputError, "rgb.txt:1: expected a number for the timestamp, got 'abc'",
       write("seq/rgb.txt", "abc rgb/000000.png\n")},
      {"sequence", "timestamps_decrease", E::kInputError, "depth.txt:2: timestamp 0.000000 is not after",
       write("seq/depth.txt", "0.0333 depth/000001.png\n0.0 depth/000000.png\n")},
      {"sequence", "binary_garbage_list", E::kInputError, "depth.txt:1",
       write("seq/depth.txt", std::string("\x00\xff\x13 \x80\n", 6))},
      {"sequence", "empty_depth_list", E::kInputError, "lists no frames", write("seq/depth.txt", "# none\n")},
      {"sequence", "no_pose_near_any_frame", E::kInputError, "3 without a ground-truth pose",
       write("seq/groundtruth.txt", "100.0 0 0 0 0 0 0 1\n")},
      {"sequence", "bad_associations", E::kInputError, "associations.txt:1",
       write("seq/associations.txt", "0.0 rgb/000000.png 0.0\n")},
      {"sequence", "image_missing", E::kInputError, "rgb.txt:3: image 'rgb/000001.png' does not exist",
       removeFile("seq/rgb/000001.png")},
      // Names the file system cannot look up are the list's error, not a std::filesystem
      // exception (the fuzzer found these: libFuzzer saw an uncaught filesystem_error).
      {"sequence", "image_in_symlink_loop", E::kInputError,
       "depth.txt:1: image 'loop/000000.png' cannot be read: Too many levels of symbolic links",
       [](const fs::path& d) {
         fs::create_symlink("loop", d / "seq/loop");
         return write("seq/depth.txt", "0.0 loop/000000.png\n")(d);
       }},
      {"sequence", "image_name_too_long", E::kInputError, "depth.txt:1: image 'aaaa",
       write("seq/depth.txt", "0.0 " + std::string(5000, 'a') + "\n")},
      // Images (decoded lazily: load(0)).
      {"sequence", "corrupt_depth_png", E::kInputError, "depth/000000.png: cannot decode depth image",
       write("seq/depth/000000.png", "\x89PNG\r\n garbage")},
      {"sequence", "empty_rgb_png", E::kInputError, "rgb/000000.png: cannot decode colour image",
       write("seq/rgb/000000.png", "")},
      {"sequence", "depth_8bit_colour", E::kInputError,
       "depth/000000.png: depth image must be 16-bit single-channel, got 8-bit 3-channel",
       image("seq/depth/000000.png", cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)))},
      {"sequence", "depth_wrong_size", E::kInputError, "depth/000000.png: depth image is 32x24 but the camera is 64x48",
       image("seq/depth/000000.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(1000)))},
      {"sequence", "rgb_wrong_size", E::kInputError, "colour image is",
       image("seq/rgb/000000.png", cv::Mat(10, 10, CV_8UC3, cv::Scalar(1, 2, 3)))},
      // Damaged images are one error naming the file (a JPEG cut to 2/3 was once mapped
      // with libjpeg's grey fill and an anonymous warning; a cut PNG printed a libpng line).
      {"sequence", "rgb_jpeg_cut", E::kInputError,
       "rgb/000000.png: cannot decode colour image: Premature end of JPEG file",
       cutImage("seq/rgb/000000.png", texture(), ".jpg", 2.0 / 3)},
      {"sequence", "rgb_png_cut", E::kInputError, "rgb/000000.png: cannot decode colour image: the file ends early",
       cutImage("seq/rgb/000000.png", texture(), ".png", 2.0 / 3)},
      {"sequence", "rgb_png_cut_before_iend", E::kInputError, "rgb/000000.png: cannot decode colour image",
       [](const fs::path& d) {
         const std::string bytes = readFile(d / "seq/rgb/000000.png");
         writeText(d / "seq/rgb/000000.png", bytes.substr(0, bytes.size() - 12));  // the IEND chunk
         return std::string();
       }},
      {"sequence", "depth_png_cut", E::kInputError, "depth/000000.png: cannot decode depth image: the file ends early",
       cutImage("seq/depth/000000.png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(7000)), ".png", 2.0 / 3)},
      {"sequence", "depth_png_bit_flip", E::kInputError, "depth/000000.png: cannot decode depth image",
       [](const fs::path& d) {
         std::string bytes = readFile(d / "seq/depth/000000.png");
         bytes[bytes.size() / 2] ^= 0x10;  // inside the pixel data: its CRC no longer matches
         writeText(d / "seq/depth/000000.png", bytes);
         return std::string();
       }},
      {"sequence", "depth_as_jpeg", E::kInputError, "depth image must be 16-bit single-channel, got 8-bit 3-channel (JPEG)",
       cutImage("seq/depth/000000.png", texture(), ".jpg", 1.0)},
      {"sequence", "rgb_not_an_image", E::kInputError, "rgb/000000.png: cannot decode colour image: not a PNG or JPEG file",
       write("seq/rgb/000000.png", "GIF89a")},
      {"sequence", "camera_file_missing_key", E::kInputError, "camera.yaml: missing key 'cy'",
       write("seq/camera.yaml", "fx: 50\nfy: 50\ncx: 31.5\ndepth_scale: 5000\nwidth: 64\nheight: 48\n")},
      // Poses (TUM trajectories: ground truth, corrected trajectories).
      {"trajectory", "missing_file", E::kInputError, "cannot open", removeFile("poses.txt")},
      {"trajectory", "zero_quaternion", E::kInputError, "poses.txt:1: quaternion (qx qy qz qw) has zero norm",
       write("poses.txt", "0.5 1 2 3 0 0 0 0\n")},
      {"trajectory", "nan", E::kInputError, "poses.txt:1: ty is not finite", write("poses.txt", "0.5 1 nan 3 0 0 0 1\n")},
      {"trajectory", "inf", E::kInputError, "is not finite", write("poses.txt", "0.5 1 2 inf 0 0 0 1\n")},
      {"trajectory", "seven_columns", E::kInputError, "expected 'timestamp tx ty tz qx qy qz qw'",
       write("poses.txt", "0.5 1 2 3 0 0 0\n")},
      {"trajectory", "number_with_suffix", E::kInputError, "expected a number",
       write("poses.txt", "0.5 1 2 3x 0 0 0 1\n")},
      {"trajectory", "repeated_timestamp", E::kInputError, "timestamps must increase",
       write("poses.txt", "0.5 1 2 3 0 0 0 1\n0.5 1 2 3 0 0 0 1\n")},
      {"corrected_trajectory", "matches_no_keyframe", E::kInputError, "no pose matches a keyframe timestamp",
       write("poses.txt", "50.0 1 2 3 0 0 0 1\n")},
      // Trajectory pairs (vdmap eval --trajectory EST --groundtruth GT).
      {"trajectory_pair", "no_common_timestamps", E::kInputError,
       "est.txt: 0 of 3 poses match a ground-truth timestamp within 0.02 s; at least 3 are needed for the alignment "
       "(ground truth: ",
       write("est.txt", "10.0 1 2 3 0 0 0 1\n10.1 1 2 3.1 0 0 0 1\n10.2 1.1 2 3.2 0 0 0 1\n")},
      {"trajectory_pair", "two_common_timestamps", E::kInputError, "est.txt: 2 of 3 poses match",
       write("est.txt", "0.0 1 2 3 0 0 0 1\n0.1 1 2 3.1 0 0 0 1\n10.2 1.1 2 3.2 0 0 0 1\n")},
      {"trajectory_pair", "groundtruth_missing", E::kInputError, "gt.txt: cannot open", removeFile("gt.txt")},
      {"trajectory_pair", "groundtruth_malformed", E::kInputError, "gt.txt:2: expected 'timestamp tx ty tz qx qy qz qw'",
       write("gt.txt", "0.005 1 2 3 0 0 0 1\n0.105 1 2 3.1\n")},
      // Camera files (the configuration files vdmap reads).
      {"camera_yaml", "missing_file", E::kInputError, "cannot open camera file", removeFile("camera.yaml")},
      {"camera_yaml", "missing_key", E::kInputError, "camera.yaml: missing key 'cy'",
       write("camera.yaml", "fx: 500\nfy: 501\ncx: 320\ndepth_scale: 1000\nwidth: 640\nheight: 480\n")},
      {"camera_yaml", "value_not_a_number", E::kInputError, "camera.yaml:1: key 'fx' must be a number",
       write("camera.yaml", "fx: fast\nfy: 1\ncx: 1\ncy: 1\ndepth_scale: 1\nwidth: 1\nheight: 1\n")},
      {"camera_yaml", "negative_focal_length", E::kInputError, "fx", write("camera.yaml", "preset: 7scenes\nfx: -3\n")},
      {"camera_yaml", "colour_missing_key", E::kInputError, "camera.yaml:1: colour: missing key 'cy'",
       write("camera.yaml", "colour: {fx: 525, fy: 525, cx: 320}\nfx: 500\nfy: 500\ncx: 320\ncy: 240\ndepth_scale: 1000\nwidth: 640\nheight: 480\n")},
      {"camera_yaml", "colour_not_a_map", E::kInputError, "key 'colour' must be a map",
       write("camera.yaml", "preset: 7scenes\ncolour: yes\n")},
      {"camera_yaml", "colour_pose_not_a_rotation", E::kInputError, "colour: T_colour_depth is not a finite rigid transform",
       write("camera.yaml", "preset: 7scenes\ncolour: {fx: 525, fy: 525, cx: 320, cy: 240, T_colour_depth: [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]}\n")},
      {"camera_yaml", "colour_pose_eleven_numbers", E::kInputError, "colour: T_colour_depth must be 12 numbers",
       write("camera.yaml", "preset: 7scenes\ncolour: {fx: 525, fy: 525, cx: 320, cy: 240, T_colour_depth: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}\n")},
      {"camera_yaml", "unknown_preset", E::kInputError, "unknown camera preset 'kinect9'",
       write("camera.yaml", "preset: kinect9\n")},
      {"camera_yaml", "not_a_map", E::kInputError, "expected a map of camera keys", write("camera.yaml", "- 1\n- 2\n")},
      {"camera_yaml", "empty", E::kInputError, "camera.yaml", write("camera.yaml", "")},
      {"camera_yaml", "fractional_width", E::kInputError, "width",
       write("camera.yaml", "fx: 500\nfy: 501\ncx: 320\ncy: 240\ndepth_scale: 1000\nwidth: 640.5\nheight: 480\n")},
      {"camera_yaml", "unknown_key", E::kInputError, "camera.yaml:2: unknown key 'focal' (valid keys: preset, fx,",
       write("camera.yaml", "preset: tum-fr1\nfocal: 500\n")},
      {"camera_yaml", "colour_unknown_key", E::kInputError, "camera.yaml:1: unknown key 'k1' in 'colour' (valid keys: fx,",
       write("camera.yaml", "colour: {fx: 525, fy: 525, cx: 320, cy: 240, k1: 0.1}\npreset: 7scenes\n")},
      {"camera_yaml", "principal_point_outside", E::kInputError, "principal point (cx 5000, cy 240) must lie within the 640x480 image",
       write("camera.yaml", "preset: tum-fr1\ncx: 5000\ncy: 240\n")},
      {"camera_json", "unknown_key_in_camera_block", E::kInputError, "unknown key 'focal' in 'camera'",
       write("camera.json", "{\"camera\": {\"preset\": \"replica\", \"focal\": 500}, \"mapping\": {\"any\": 1}}")},
      {"camera_json", "syntax_error", E::kInputError, "not valid YAML/JSON", write("camera.json", "{\"fx\": [1, 2")},
      // PLY meshes (vdmap synth --mesh, vdmap eval) and ellipsoid maps (vdmap render --map).
      {"ply_mesh", "missing_file", E::kInputError, "cannot open the file", removeFile("m.ply")},
      {"ply_mesh", "not_ply", E::kInputError, "m.ply:1: not a PLY file", write("m.ply", "solid cube\n")},
      {"ply_mesh", "no_end_header", E::kInputError, "does not end with 'end_header'",
       write("m.ply", "ply\nformat ascii 1.0\nelement vertex 3\n")},
      {"ply_mesh", "binary_without_end_header", E::kInputError, "unexpected header line '\\x01\\x02\\xff",
       write("m.ply", std::string("ply\nformat binary_little_endian 1.0\nelement vertex 3\n\x01\x02\xff\x7f\x80 data", 63))},
      {"ply_mesh", "unknown_format", E::kInputError, "unknown format 'binary_middle_endian'",
       write("m.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n")},
      {"ply_mesh", "unknown_property_type", E::kInputError, "known type",
       write("m.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n")},
      {"ply_mesh", "ascii_non_number", E::kInputError, "non-number",
       write("m.ply", replaceAll(kMeshPly, "1 0 0 0 255 0", "1 zero 0 0 255 0"))},
      {"ply_mesh", "binary_truncated", E::kInputError, "truncated", write("m.ply", binaryMesh(std::string(30, '\0')))},
      {"ply_mesh", "no_faces", E::kInputError, "the mesh has no faces",
       write("m.ply", kMeshPly.substr(0, kMeshPly.find("element face")) + "end_header\n0 0 0 1 2 3\n0 0 0 1 2 3\n0 0 0 1 2 3\n")},
      {"ply_mesh", "no_colours", E::kInputError, "no vertex colours",
       write("m.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")},
      {"ply_mesh", "face_index_out_of_range", E::kInputError, "a face indexes vertex 7 of 3",
       write("m.ply", kMeshPly.substr(0, kMeshPly.rfind("3 0 1 2")) + "3 0 1 7\n")},
      {"ply_mesh", "huge_vertex_count", E::kInputError, "element 'vertex' has 1000000000000 records",
       write("m.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
                      "end_header\n")},
      {"ply_mesh", "element_without_properties", E::kInputError, "element 'vertex' has no properties",
       write("m.ply", "ply\nformat ascii 1.0\nelement vertex 1000000000000\nend_header\n")},
      {"ply_mesh", "nan_colour", E::kInputError, "is not finite",
       write("m.ply", binaryMesh(std::string(12, '\0') + std::string("\x00\x00\xc0\x7f", 4) + std::string(8, '\0') +
                                 std::string(24 * 2, '\0') + std::string("\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00", 13)))},
      {"ply_mesh", "float_face_index_overflow", E::kInputError, "list item out of range",
       write("m.ply", replaceAll(replaceAll(kMeshPly, "uchar int vertex_indices", "uchar float vertex_indices"),
                                 "3 0 1 2", "3 0 1 1e30"))},
      {"ply_ellipsoids", "no_covariance", E::kInputError, "needs the covariance", write("e.ply", kMeshPly)},
      {"ply_ellipsoids", "truncated", E::kInputError, "truncated",
       [](const fs::path& d) {
         const std::string bytes = readFile(d / "e.ply");
         writeText(d / "e.ply", bytes.substr(0, bytes.size() - 7));
         return std::string();
       }},
      {"ply_ellipsoids", "negative_count", E::kInputError, "count",
       write("e.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                      "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float cxx\n"
                      "property float cxy\nproperty float cxz\nproperty float cyy\nproperty float cyz\n"
                      "property float czz\nproperty int count\nproperty int keyframe\nend_header\n"
                      "0 0 1 1 2 3 1 0 0 1 0 1 -5 0\n")},
      // Session files (.vdmap).
      {"session", "missing_file", E::kInputError, "cannot open the session file", removeFile("s.vdmap")},
      {"session", "empty", E::kInputError, "wrong magic", write("s.vdmap", "")},
      {"session", "wrong_magic", E::kInputError, "wrong magic", write("s.vdmap", "ply\nformat ascii 1.0\n")},
      {"session", "truncated_header", E::kInputError, "header: truncated", session([](std::string* b) { b->resize(20); })},
      {"session", "truncated_section", E::kInputError, "truncated", session([](std::string* b) { b->resize(b->size() - 9); })},
      {"session", "flipped_byte", E::kInputError, "checksum mismatch", session([](std::string* b) { (*b)[b->size() / 2] ^= 4; })},
      {"session", "newer_version", E::kInputError, "format version 8 is newer",
       session([](std::string* b) {
         setU32(b, 8, 8);
         setU32(b, 20, crc32(std::string_view(*b).substr(0, 20)));
       })},
      {"session", "trailing_bytes", E::kInputError, "unexpected bytes at the end", session([](std::string* b) { *b += "x"; })},
      // Command-line values.
      {"command_line", "frames_reversed", E::kCliUsage, "--frames: '5:2': the end must be after the start", args("map {dir}/seq --out {dir}/out --frames 5:2")},
      {"command_line", "frames_past_the_end", E::kCliError, "--frames starts at 9", args("map {dir}/seq --out {dir}/out --frames 9:")},
      {"command_line", "unknown_camera_preset", E::kCliUsage, "--camera: unknown camera preset 'nope'",
       args("map {dir}/seq --out {dir}/out --camera nope")},
      {"command_line", "cell_size_zero", E::kCliUsage, "cell_size must be >= 1 px", args("map {dir}/seq --out {dir}/out --cell-size 0")},
      {"command_line", "negative_keyframe_every", E::kCliUsage, "--keyframe-every: keyframe_every must be >= 0",
       args("map {dir}/seq --out {dir}/out --keyframe-every -1")},
      {"command_line", "negative_merge_distance", E::kCliUsage, "merge_distance must be >= 0",
       args("map {dir}/seq --out {dir}/out --merge-distance -1")},
      {"command_line", "depth_range_reversed", E::kCliError, "depth range must satisfy 0 <= min < max",
       args("map {dir}/seq --out {dir}/out --min-depth 5 --max-depth 1")},
      {"command_line", "tau_above_one", E::kCliUsage, "--tau: tau must be within 0..1",
       args("map {dir}/seq --out {dir}/out --tau 2")},
      {"command_line", "samples_negative", E::kCliUsage, "--samples", args("bench {dir}/seq --samples -5")},
      {"command_line", "unknown_sensor_model", E::kCliUsage, "foo", args("map {dir}/seq --out {dir}/out --sensor-model foo")},
      {"command_line", "out_is_a_file", E::kCliError, "is not a folder", args("map {dir}/seq --out {dir}/seq/rgb.txt")},
      {"command_line", "save_into_missing_folder", E::kCliError, "its folder does not exist (--save)",
       args("map {dir}/seq --out {dir}/out --save {dir}/no/such/s.vdmap")},
      {"command_line", "cell_size_not_a_number", E::kCliUsage, "--cell-size", args("map {dir}/seq --out {dir}/out --cell-size abc")},
      {"command_line", "missing_out", E::kCliUsage, "--out", args("map {dir}/seq")},
      {"command_line", "unknown_verb", E::kCliUsage, "frobnicate", args("frobnicate")},
      {"command_line", "render_sigma_not_a_number", E::kCliUsage, "--sigma: must be a number > 0, got nan",
       args("render --map {dir}/e.ply --out {dir}/o.png --sigma nan")},
      {"command_line", "render_out_in_missing_folder", E::kCliError, "its folder does not exist (--out)",
       args("render {dir}/seq --out {dir}/no/such/o.png")},
      {"command_line", "eval_trajectory_without_groundtruth", E::kCliUsage, "--groundtruth",
       args("eval --trajectory {dir}/seq/groundtruth.txt")},
      {"command_line", "eval_trajectory_and_map", E::kCliUsage, "excludes",
       args("eval --trajectory {dir}/seq/groundtruth.txt --groundtruth {dir}/seq/groundtruth.txt --map {dir}/e.ply "
            "--mesh {dir}/seq/groundtruth.txt")},
      {"command_line", "eval_nothing", E::kCliUsage, "nothing to evaluate", args("eval")},
      {"command_line", "eval_trajectory_offset_matches_nothing", E::kCliError, "groundtruth.txt: 0 of 3 poses match",
       args("eval --trajectory {dir}/seq/groundtruth.txt --groundtruth {dir}/seq/groundtruth.txt --offset 100")},
      {"command_line", "eval_trajectory_zero_max_difference", E::kCliUsage, "--max-difference: must be a number > 0",
       args("eval --trajectory {dir}/seq/groundtruth.txt --groundtruth {dir}/seq/groundtruth.txt --max-difference 0")},
      {"command_line", "bench_unknown_pose_source", E::kCliUsage, "--poses", args("bench {dir}/seq --poses imu")},
      {"command_line", "render_bad_size", E::kCliUsage, "--size: '10': expected WIDTHxHEIGHT", args("render --map {dir}/e.ply --out {dir}/o.png --size 10")},
      // Smaller items.
      {"command_line", "octomap_zero", E::kCliUsage, "--octomap: the resolution must be > 0 and at most 1 m",
       args("map {dir}/seq --out {dir}/out --octomap 0")},
      {"command_line", "octomap_negative", E::kCliUsage, "--octomap: the resolution must be > 0 and at most 1 m",
       args("map {dir}/seq --out {dir}/out --octomap -1")},
      {"command_line", "octomap_finer_than_the_keys_hold", E::kCliError, "is too fine for this map",
       args("map {dir}/seq --out {dir}/out --octomap 1e-9")},
      {"command_line", "frames_end_past_the_end", E::kCliError, "--frames 1:9 ends past the sequence: it lists 3 depth frames (0:3)",
       args("map {dir}/seq --out {dir}/out --frames 1:9")},
      {"command_line", "frames_zero_count", E::kCliUsage, "N means the first N frames", args("map {dir}/seq --out {dir}/out --frames 0")},
      {"command_line", "render_without_out", E::kCliUsage, "--out is required", args("render {dir}/seq")},
      // The point queries' slice plane (docs/workbench.md "Queries").
      {"command_line", "render_query_slice_bad_axis", E::kCliUsage, "--query-slice: 'w=1': expected AXIS=VALUE",
       args("render --map {dir}/e.ply --out {dir}/o.png --query-slice w=1")},
      {"command_line", "render_query_slice_bad_color", E::kCliUsage, "--query-slice-color: 'height': expected occupancy or distance",
       args("render --map {dir}/e.ply --out {dir}/o.png --query-slice z=1 --query-slice-color height")},
      {"command_line", "render_out_under_a_file", E::kCliError, "seq/rgb.txt is a file, not a folder (--out)",
       args("render {dir}/seq --out {dir}/seq/rgb.txt/x.png")},
      {"command_line", "load_missing_session", E::kCliError, "no such session file (--load)",
       args("map {dir}/seq --out {dir}/out --load {dir}/none.vdmap")},
      {"command_line", "load_not_a_session", E::kCliError, "not a vdmap session file (--load)",
       args("map {dir}/seq --out {dir}/out --load {dir}/seq/rgb.txt")},
      {"command_line", "render_folder_without_a_map", E::kCliError, "has no global_ellipsoids.ply",
       args("render --map {dir}/seq --out {dir}/o.png")},
      {"command_line", "synth_frames_past_the_trajectory", E::kCliError, "ends past the trajectory: it has 3 poses (0:3)",
       args("synth --builtin --builtin-frames 3 --frames 0:5 --out {dir}/out")},
      // Damaged images through the command line: the one line is vdmap's, no library's.
      {"command_line", "map_rgb_jpeg_cut", E::kCliError, "rgb/000000.png: cannot decode colour image",
       then(cutImage("seq/rgb/000000.png", texture(), ".jpg", 2.0 / 3), "map {dir}/seq --out {dir}/out")},
      {"command_line", "map_depth_png_cut", E::kCliError, "depth/000001.png: cannot decode depth image",
       then(cutImage("seq/depth/000001.png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(7000)), ".png", 0.5),
            "map {dir}/seq --out {dir}/out")},
      // Poses out of range.
      {"trajectory", "translation_too_far", E::kInputError, "poses.txt:1: tx is '1e300' m: a pose must lie within 10000 m",
       write("poses.txt", "0.5 1e300 2 3 0 0 0 1\n")},
      {"trajectory", "translation_just_too_far", E::kInputError, "poses.txt:2: tz is '-10000.5' m",
       write("poses.txt", "0.5 1 2 3 0 0 0 1\n0.6 1 2 -10000.5 0 0 0 1\n")},
      {"trajectory", "quaternion_overflows", E::kInputError, "poses.txt:1: quaternion (qx qy qz qw) is too large to normalise",
       write("poses.txt", "0.5 1 2 3 0 0 1e300 1e300\n")},
      {"trajectory", "timestamp_too_large", E::kInputError, "poses.txt:1: timestamp 1e+300 is out of range",
       write("poses.txt", "1e300 1 2 3 0 0 0 1\n")},
      {"sequence", "associations_rgb_timestamp_in_nanoseconds", E::kInputError,
       "associations.txt:1: timestamp 1.7e+18 is out of range",
       write("seq/associations.txt", "1.7e18 rgb/000000.png 0.0 depth/000000.png\n")},
      {"sequence", "groundtruth_far_away", E::kInputError, "groundtruth.txt:2: ty is '1e300' m",
       write("seq/groundtruth.txt", "0.000000 0 0 0 0 0 0 1\n0.033333 0 1e300 0 0 0 0 1\n0.066667 0 0 0 0 0 0 1\n")},
      {"command_line", "map_groundtruth_far_away", E::kCliError, "groundtruth.txt:2: tx is '1e300' m",
       then(write("seq/groundtruth.txt", "0.000000 0 0 0 0 0 0 1\n0.033333 1e300 0 0 0 0 0 1\n0.066667 0 0 0 0 0 0 1\n"),
            "map {dir}/seq --out {dir}/out")},
      // Sequence messages that named the wrong thing.
      {"sequence", "depth_image_is_a_folder", E::kInputError, "depth.txt:3: image 'depth/000001.png' is a folder, not an image file",
       [](const fs::path& d) {
         fs::remove(d / "seq/depth/000001.png");
         fs::create_directory(d / "seq/depth/000001.png");
         return std::string();
       }},
      {"sequence", "empty_rgb_list", E::kInputError, "seq/rgb.txt: lists no frames", write("seq/rgb.txt", "# none\n")},
      // A damaged session where a session is one of the things a verb takes: named as one.
      {"command_line", "render_session_first_byte_flipped", E::kCliError, "s.vdmap: a damaged session file: it does not start",
       then(session([](std::string* b) { (*b)[0] ^= 0x01; }), "render {dir}/s.vdmap --out {dir}/o.png")},
      {"command_line", "render_map_session_empty", E::kCliError, "s.vdmap: a damaged session file: it is empty",
       then(session([](std::string* b) { b->clear(); }), "render --map {dir}/s.vdmap --out {dir}/o.png")},
      {"command_line", "load_session_wrong_magic", E::kCliError, "s.vdmap: a damaged session file",
       then(session([](std::string* b) { b->replace(0, 8, "VDMAPXXX"); }),
            "map {dir}/seq --out {dir}/out --load {dir}/s.vdmap")},
      // --load on a sequence that is not where the session stopped.
      {"command_line", "load_on_another_folder", E::kCliError, "other: is not the recording",
       then(savedSession("0:2", "other"), "map {dir}/other --out {dir}/out --load {dir}/s.vdmap")},
      {"command_line", "load_on_another_recording_of_that_name", E::kCliError,
       "depth frame 1 is at t = 10.033333 s, but",
       then(savedSession("0:2", "b/seq", 10.0), "map {dir}/b/seq --out {dir}/out --load {dir}/s.vdmap")},
      {"command_line", "load_on_a_shorter_recording", E::kCliError, "lists 1 depth frame, but",
       then(savedSession("0:2", "b/seq", 0.0, 1), "map {dir}/b/seq --out {dir}/out --load {dir}/s.vdmap")},
      {"command_line", "load_a_finished_session", E::kCliError, "s.vdmap already covers the whole sequence",
       then(savedSession("0:3", ""), "map {dir}/seq --out {dir}/out --load {dir}/s.vdmap")},
      // Option values and camera files. A value wrong by itself is CLI11's error, checked before
      // any work; one that needs the data is exit 1. None is taken silently or replaced.
      {"command_line", "frames_past_an_int", E::kCliUsage,
       "--frames: '0:1000000000000': frame number 1000000000000 is out of range (0..2147483647)",
       args("map {dir}/seq --out {dir}/out --frames 0:1000000000000")},
      {"command_line", "octomap_coarser_than_a_metre", E::kCliUsage, "--octomap: the resolution must be > 0 and at most 1 m",
       args("map {dir}/seq --out {dir}/out --octomap 1e9")},
      {"command_line", "render_out_jpeg_2000", E::kCliUsage, "the image format follows the extension: .png, or .jpg",
       args("render --map {dir}/e.ply --out {dir}/o.jp2")},
      {"command_line", "render_unknown_color", E::kCliUsage, "--color: unknown colour mode 'red'",
       args("render --map {dir}/e.ply --out {dir}/o.png --color red")},
      {"command_line", "render_bad_view", E::kCliUsage, "--view: 'keyframe': expected global, keyframe:K or container:K",
       args("render {dir}/seq --out {dir}/o.png --view keyframe")},
      {"command_line", "synth_builtin_frames_zero", E::kCliUsage, "--builtin-frames: Value 0 not in range 2 to",
       args("synth --builtin --builtin-frames 0 --out {dir}/out")},
      {"command_line", "synth_builtin_frames_negative", E::kCliUsage, "--builtin-frames: Value -5 not in range 2 to",
       args("synth --builtin --builtin-frames -5 --out {dir}/out")},
      {"command_line", "synth_builtin_laps_zero", E::kCliUsage, "--builtin-laps: Value 0 not in range 1 to",
       args("synth --builtin --builtin-laps 0 --out {dir}/out")},
      {"command_line", "synth_builtin_frames_without_builtin", E::kCliUsage, "--builtin-frames requires --builtin",
       args("synth --builtin-frames 30 --out {dir}/out")},
      {"command_line", "synth_seed_negative", E::kCliUsage, "--seed: expected a whole number 0..2^64-1, got '-1'",
       args("synth --builtin --builtin-frames 3 --seed -1 --out {dir}/out")},
      {"command_line", "synth_unknown_noise", E::kCliUsage, "--noise: kinect not in",
       args("synth --builtin --builtin-frames 3 --noise kinect --out {dir}/out")},
      {"command_line", "bench_keyframe_every_zero", E::kCliUsage, "--keyframe-every: Value 0 not in range 1 to",
       args("bench {dir}/seq --out {dir}/out --keyframe-every 0")},
      // bench --query (the point queries against OctoMap and ground truth)
      {"command_line", "bench_query_points_zero", E::kCliUsage, "--query-points: Value 0 not in range",
       args("bench {dir}/seq --query --query-points 0 --out {dir}/out")},
      {"command_line", "bench_truth_without_mesh", E::kCliUsage, "--truth requires --mesh",
       args("bench {dir}/seq --query --truth {dir}/seq --out {dir}/out")},
      {"command_line", "eval_mesh_missing", E::kCliError, "none.ply: cannot open the file",
       then(write("p.ply", kMeshPly), "eval --map {dir}/p.ply --mesh {dir}/none.ply")},
      // Thread counts, camera files and --refine: none is taken silently or printed on by a library.
      {"command_line", "threads_65537", E::kCliUsage, "--threads: Value 65537 not in range 0 to 256",
       args("map {dir}/seq --out {dir}/out --threads 65537")},
      {"command_line", "threads_negative", E::kCliUsage, "--threads: Value -1 not in range 0 to 256",
       args("map {dir}/seq --out {dir}/out --threads -1")},
      {"command_line", "refine_with_ground_truth_poses", E::kCliError,
       "--refine pairwise refines tracked poses (--poses track); this run maps the ground-truth poses",
       args("map {dir}/seq --out {dir}/out --refine pairwise")},
      {"command_line", "refine_with_explicit_gt_poses", E::kCliError, "--refine joint refines tracked poses",
       args("map {dir}/seq --out {dir}/out --poses gt --refine joint")},
      {"command_line", "render_refine_with_ground_truth_poses", E::kCliError, "--refine pairwise refines tracked poses",
       args("render {dir}/seq --out {dir}/o.png --refine pairwise")},
      {"command_line", "bench_refine_with_ground_truth_poses", E::kCliError, "--refine pairwise refines tracked poses",
       args("bench {dir}/seq --out {dir}/out --refine pairwise")},
      // gui --settings FILE and --view-file V.json: read strictly, before the display is looked at (the
      // user's own settings file only warns).
      {"command_line", "gui_settings_missing", E::kCliError, "none.json: no such file",
       args("gui {dir}/seq --settings {dir}/none.json --exit")},
      {"command_line", "gui_settings_out_of_range", E::kCliError, "bad.json: thresholds.merge_distance must be >= 0",
       then(write("bad.json", R"({"thresholds": {"merge_distance": -1}})"), "gui {dir}/seq --settings {dir}/bad.json --exit")},
      // Height slice: settings keys slice_lo < slice_hi.
      {"command_line", "gui_settings_slice_reversed", E::kCliError,
       "bad.json: view.slice_lo must be below view.slice_hi (metres above the floor, within 1e4)",
       then(write("bad.json", R"({"view": {"slice": true, "slice_lo": 2, "slice_hi": 1}})"),
            "gui {dir}/seq --settings {dir}/bad.json --exit")},
      {"command_line", "gui_view_file_missing_key", E::kCliError, "v.json: missing key 'source'",
       then(write("v.json", R"({"vdmap_view": 1})"), "gui {dir}/seq --view-file {dir}/v.json --exit")},
      // Opening map files (gui PATH, render --map): a bad one is one line before the window opens.
      {"command_line", "gui_bt_corrupt", E::kCliError, "m.bt: corrupt OctoMap: the tree data ends early (truncated?)",
       then(write("m.bt", std::string("# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\ndata\n\x03")),
            "gui {dir}/m.bt --exit")},
      {"command_line", "gui_ply_no_vertices", E::kCliError, "p.ply: has no vertices (expected at least one point)",
       then(write("p.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                           "property float z\nend_header\n"),
            "gui {dir}/p.ply --exit")},
      {"command_line", "gui_unknown_file_kind", E::kCliError, "notes.txt: is of no kind vdmap opens",
       then(write("notes.txt", "hello\n"), "gui {dir}/notes.txt --exit")},
      {"command_line", "gui_view_file_as_path", E::kCliError, "v.json: is a view file: give it with --view-file",
       then(viewFile([](nlohmann::json&) {}), "gui {dir}/v.json --exit")},
      {"command_line", "render_map_bt_not_an_octomap", E::kCliError, "m.bt:1: not an OctoMap .bt file",
       then(write("m.bt", "hello\n"), "render --map {dir}/m.bt --out {dir}/o.png")},
      // gui --measure X1,Y1,X2,Y2 (measuring): four view pixels or nothing.
      {"command_line", "gui_measure_three_numbers", E::kCliUsage, "--measure: '1,2,3': expected X1,Y1,X2,Y2",
       args("gui {dir}/seq --measure 1,2,3 --exit")},
      {"command_line", "gui_measure_negative", E::kCliUsage, "--measure: '1,2,-3,4': expected X1,Y1,X2,Y2",
       args("gui {dir}/seq --measure 1,2,-3,4 --exit")},
      {"sequence", "camera_file_unknown_key", E::kInputError,
       "camera.yaml:2: unknown key 'focal' (valid keys: preset, fx, fy, cx, cy, depth_scale, scale, width, w, height, h, "
       "colour)",
       write("seq/camera.yaml", "preset: tum-fr1\nfocal: 500\n")},
      {"sequence", "camera_file_principal_point_outside", E::kInputError,
       "camera.yaml: camera: principal point (cx 5000, cy 23.5) must lie within the 64x48 image",
       write("seq/camera.yaml", "fx: 50\nfy: 50\ncx: 5000\ncy: 23.5\ndepth_scale: 5000\nwidth: 64\nheight: 48\n")},
      // Golden images and suites (`vdmap render --expect` / `--suite`): a golden that cannot be
      // compared and a suite that cannot run are bad input (exit 1), found before anything is
      // rendered or written; option misuse is CLI11's. The session is the matrix's good one.
      {"session", "render_golden_other_size", E::kCliError, "g.png: the golden is 320x240, the view 160x120 (--size, or --update)",
       then(image("g.png", cv::Mat(240, 320, CV_8UC3, cv::Scalar(10, 20, 30))),
            "render {dir}/s.vdmap --size 160x120 --expect {dir}/g.png")},
      {"session", "render_golden_corrupt_png", E::kCliError, "g.png: cannot decode colour image",
       then(cutImage("g.png", texture(), ".png", 0.5), "render {dir}/s.vdmap --size 64x48 --expect {dir}/g.png")},
      {"session", "render_golden_missing", E::kCliError, "g.png: no such golden image (render it once with --update)",
       args("render {dir}/s.vdmap --expect {dir}/g.png")},
      {"session", "render_suite_missing_map", E::kCliError, "views.yaml:4: map 'kitchen': no such file or folder",
       then(write("views.yaml", "version: 1\nout: out\nmaps:\n  kitchen: missing.vdmap\nviews:\n  - {name: a, map: kitchen}\n"),
            "render --suite {dir}/views.yaml")},
      {"session", "render_suite_yaml_syntax", E::kCliError, "views.yaml:4: not valid YAML",
       then(write("views.yaml", "version: 1\nout: out\nviews: [{name: a, map: s\nmaps: {s: s.vdmap}\n"),
            "render --suite {dir}/views.yaml")},
      {"session", "render_suite_unknown_view_key", E::kCliError, "views.yaml:5: unknown view key 'colour'",
       then(write("views.yaml", "version: 1\nout: out\nmaps: {s: s.vdmap}\nviews:\n  - {name: a, map: s, colour: rgb}\n"),
            "render --suite {dir}/views.yaml --update")},
      {"session", "render_select_outside_the_graph", E::kCliError, "--select 99: ",
       args("render {dir}/s.vdmap --select 99 --out {dir}/o.png")},
      {"session", "render_diff_not_png", E::kCliUsage, "--diff: '",
       args("render {dir}/s.vdmap --expect {dir}/g.png --diff {dir}/d.jpg")},
      {"session", "query_resolution_in_hexadecimal", E::kCliUsage,
       "--resolution: '0x10': a number in another base (hexadecimal, binary, octal); write it in decimal",
       args("query {dir}/s.vdmap --op octomap --resolution 0x10 --out {dir}/o.bt")},
      {"session", "render_suite_duplicate_key", E::kCliError, "views.yaml:7: key 'color' is given twice in one map",
       then(write("views.yaml", "version: 1\nout: out\nmaps: {s: s.vdmap}\nviews:\n  - name: a\n    color: rgb\n    "
                                "color: height\n    map: s\n"),
            "render --suite {dir}/views.yaml --update")},
      // Settings and view files are read strictly: a misspelt key or section is named with the valid
      // ones, a key given twice names its line.
      {"session", "settings_unknown_key", E::kCliError,
       "set.json: unknown key 'thresholds.merge_dist' (valid: filter_sigma_factor,",
       then(write("set.json", "{\"thresholds\": {\"merge_dist\": 0.1}}"),
            "render {dir}/s.vdmap --settings {dir}/set.json --out {dir}/o.png")},
      {"session", "settings_unknown_section", E::kCliError, "set.json: unknown key 'thresholdz' (valid: last_sequence,",
       then(write("set.json", "{\"thresholdz\": {\"merge_distance\": 0.1}}"),
            "render {dir}/s.vdmap --settings {dir}/set.json --out {dir}/o.png")},
      {"session", "settings_duplicate_key", E::kCliError, "set.json:3: key 'merge_distance' is given twice in one object",
       then(write("set.json", "{\"thresholds\": {\n  \"merge_distance\": 0.1,\n  \"merge_distance\": 0.2\n}}"),
            "render {dir}/s.vdmap --settings {dir}/set.json --out {dir}/o.png")},
      {"session", "render_view_file_duplicate_key", E::kCliError, "v.json:1: key 'color' is given twice in one object",
       then(
           [](const fs::path& d) {
             viewFile([](nlohmann::json&) {})(d);
             std::string text = readFile(d / "v.json");
             text.insert(1, "\"color\": \"rgb\", ");  // the file is one line
             writeText(d / "v.json", text);
             return std::string();
           },
           "render {dir}/s.vdmap --view-file {dir}/v.json --out {dir}/o.png")},
      {"session", "render_tolerance_bad", E::kCliUsage, "--tolerance: '8': expected COUNTS,SHARE",
       args("render {dir}/s.vdmap --expect {dir}/g.png --tolerance 8")},
      {"session", "render_update_without_expect", E::kCliUsage, "--update needs --expect GOLDEN.png (or --suite)",
       args("render {dir}/s.vdmap --update --out {dir}/o.png")},
      // View files (`render --view-file`, the window's saved views): strict, naming the key.
      {"session", "render_view_file_missing_key", E::kCliError, "v.json: missing key 'sigma'",
       then(viewFile([](nlohmann::json& j) { j.erase("sigma"); }), "render {dir}/s.vdmap --view-file {dir}/v.json --out {dir}/o.png")},
      {"session", "render_view_file_non_finite", E::kCliError, "v.json: camera.eye[0] must be finite",
       then([](const fs::path& d) {
              viewFile([](nlohmann::json& j) {
                j["camera"] = {{"eye", {7, 1, 1}}, {"target", {0, 0, 0}}, {"up", {0, 0, 1}}, {"fov_y_deg", 60}};
              })(d);
              std::string text = readFile(d / "v.json");
              text.replace(text.find("[7,"), 3, "[1e999,");  // JSON has no infinity: a number too large for a double
              writeText(d / "v.json", text);
              return std::string();
            },
            "render {dir}/s.vdmap --view-file {dir}/v.json --out {dir}/o.png")},
      {"session", "render_view_file_unknown_key", E::kCliError, "v.json: unknown key 'zoom'",
       then(viewFile([](nlohmann::json& j) { j["zoom"] = 2; }), "render {dir}/s.vdmap --view-file {dir}/v.json --out {dir}/o.png")},
      // Point queries (`vdmap query`, docs/method.md 13): a bad record is one line naming the file and
      // line (a PLY: the vertex), found before the map is loaded; option misuse is CLI11's.
      {"session", "query_points_nan", E::kCliError, "pts.txt:3: y is not finite ('nan')",
       then(write("pts.txt", "# x y z\n0 0 1\n0 nan 1\n"), "query {dir}/s.vdmap --op classify --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_points_two_columns", E::kCliError, "pts.txt:2: expected x y z (--op distance), got 2 fields",
       then(write("pts.txt", "0 0 1\n0 1\n"), "query {dir}/s.vdmap --op distance --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_points_none", E::kCliError, "pts.txt: has no records (expected lines of x y z)",
       then(write("pts.txt", "# nothing\n\n"), "query {dir}/s.vdmap --op classify --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_points_missing", E::kCliError, "none.txt: no such file (--points)",
       args("query {dir}/s.vdmap --op classify --points {dir}/none.txt --out {dir}/out.txt")},
      {"session", "query_sphere_radius_zero", E::kCliError, "pts.txt:1: the radius must be > 0, got 0",
       then(write("pts.txt", "0 0 1 0 2\n"), "query {dir}/s.vdmap --op collide --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_ray_zero_direction", E::kCliError, "pts.txt:1: the direction dx dy dz is zero",
       then(write("pts.txt", "0 0 1 0 0 0\n"), "query {dir}/s.vdmap --op ray --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_ply_vertex_inf", E::kCliError, "pts.ply: element data has a value that is not finite",
       then(write("pts.ply", std::string("ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
                                         "property float y\nproperty float z\nend_header\n") +
                                 std::string("\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\0\0\0\0\0\0\x80\x7f", 24)),
            "query {dir}/s.vdmap --op classify --points {dir}/pts.ply --out {dir}/out.ply")},
      // Records lie within 10 km of the origin (as poses), so that every answer stays finite.
      {"session", "query_distance_far_point", E::kCliError, "pts.txt:2: x is 3.4e+38: query records lie within 10000 m of the origin",
       then(write("pts.txt", "0 0 1\n3.4e38 0 0\n"), "query {dir}/s.vdmap --op distance --points {dir}/pts.txt --out {dir}/out.ply")},
      {"session", "query_classify_far_point", E::kCliError, "pts.txt:1: z is -100000: query records lie within",
       then(write("pts.txt", "0 0 -1e5\n"), "query {dir}/s.vdmap --op classify --points {dir}/pts.txt --out {dir}/out.ply")},
      {"session", "query_collide_huge_radius", E::kCliError, "pts.txt:1: r is 1e+39: query records lie within",
       then(write("pts.txt", "0 0 1 1e39 2\n"), "query {dir}/s.vdmap --op collide --points {dir}/pts.txt --out {dir}/out.ply")},
      {"session", "query_ray_far_range", E::kCliError, "pts.txt:1: max_range is 1e+30: query records lie within",
       then(write("pts.txt", "0 0 1 0 0 1 1e30\n"), "query {dir}/s.vdmap --op ray --points {dir}/pts.txt --out {dir}/out.ply")},
      {"session", "query_ply_vertex_far", E::kCliError, "pts.ply: vertex 0: y is 3e+38: query records lie within",
       then(write("pts.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                             "property float z\nend_header\n0 3e38 1\n"),
            "query {dir}/s.vdmap --op distance --points {dir}/pts.ply --out {dir}/out.ply")},
      {"session", "query_ply_without_radius", E::kCliError, "pts.ply: the vertex element has no property 'radius'",
       then(write("pts.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                             "property float z\nend_header\n0 0 1\n"),
            "query {dir}/s.vdmap --op collide --points {dir}/pts.ply --out {dir}/out.ply")},
      // An output that is an input is refused before any work (the input stays as it was).
      {"session", "query_out_is_the_points", E::kCliError, "pts.txt: --out is the file --points reads",
       then(write("pts.txt", "0 0 1\n"), "query {dir}/s.vdmap --op classify --points {dir}/pts.txt --out {dir}/./pts.txt")},
      {"session", "render_out_is_the_golden", E::kCliError, "g.png: --out is the file --expect reads",
       args("render {dir}/s.vdmap --expect {dir}/g.png --out {dir}/g.png")},
      {"session", "render_diff_is_the_golden", E::kCliError, "g.png: --diff is the file --expect reads",
       args("render {dir}/s.vdmap --expect {dir}/g.png --diff {dir}/g.png")},
      {"command_line", "map_save_is_the_session_loaded", E::kCliError, "s.vdmap: --save is the file --load reads",
       args("map {dir}/seq --load {dir}/s.vdmap --out {dir}/out --save {dir}/s.vdmap")},
      {"session", "query_map_folder", E::kCliError, "not a session: vdmap query reads a session file",
       then(write("pts.txt", "0 0 1\n"), "query {dir} --op classify --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_keyframe_outside_the_graph", E::kCliError, "--keyframe 40: the session has",
       then(write("pts.txt", "0 0 1\n"), "query {dir}/s.vdmap --op classify --keyframe 40 --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_keyframe_poses_match_nothing", E::kCliError,
       "poses.txt: no pose matches a keyframe timestamp (1 pose, ",
       then([](const fs::path& d) {
              writeText(d / "pts.txt", "0 0 1\n");
              writeText(d / "poses.txt", "1000.0 0 0 0 0 0 0 1\n");
              return std::string();
            },
            "query {dir}/s.vdmap --op classify --keyframe-poses {dir}/poses.txt --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_without_points", E::kCliUsage, "--op classify needs --points FILE",
       args("query {dir}/s.vdmap --op classify --out {dir}/out.txt")},
      {"session", "query_unknown_op", E::kCliUsage, "--op: nearest not in",
       args("query {dir}/s.vdmap --op nearest --out {dir}/out.txt")},
      {"session", "query_out_extension", E::kCliUsage, "--op classify writes .txt or .ply",
       then(write("pts.txt", "0 0 1\n"), "query {dir}/s.vdmap --op classify --points {dir}/pts.txt --out {dir}/out.csv")},
      {"session", "query_grid_without_band", E::kCliUsage, "--op grid needs --band LO:HI",
       args("query {dir}/s.vdmap --op grid --out {dir}/out.yaml")},
      {"session", "query_grid_band_reversed", E::kCliUsage, "--band: '2:1': expected LO:HI with LO < HI",
       args("query {dir}/s.vdmap --op grid --band 2:1 --out {dir}/out.yaml")},
      // A grid is clipped to the map's extent along up, and refused before any query when it would
      // ask too many points or lies outside the map.
      {"session", "query_grid_too_fine", E::kCliError, "points (at most 2.68e+08): give a coarser resolution or a narrower band",
       args("query {dir}/s.vdmap --op grid --band -1e30:1e30 --resolution 0.001 --out {dir}/out.yaml")},
      {"session", "query_grid_band_outside_the_map", E::kCliError, "the band 5000:6000 m lies outside the map's",
       args("query {dir}/s.vdmap --op grid --band 5000:6000 --out {dir}/out.yaml")},
      {"command_line", "map_grid_band_beyond_any_map", E::kCliError, "--grid-band 1e30:2e30 lies beyond any map: poses lie within 10000 m",
       args("map {dir}/seq --out {dir}/out --grid 0.05 --grid-band 1e30:2e30")},
      {"command_line", "map_grid_too_fine", E::kCliError, "points (at most 2.68e+08): give a coarser resolution or a narrower band",
       args("map {dir}/seq --out {dir}/out --grid 0.0005 --grid-band -1e30:1e30")},
      {"session", "query_points_with_grid", E::kCliUsage, "--points: applies to --op classify, distance, collide and ray only",
       then(write("pts.txt", "0 0 1\n"), "query {dir}/s.vdmap --op grid --band 0:1 --points {dir}/pts.txt --out {dir}/out.yaml")},
      {"session", "query_octomap_resolution_zero", E::kCliUsage, "--resolution: must be a number > 0, got 0",
       args("query {dir}/s.vdmap --op octomap --resolution 0 --out {dir}/out.bt")},
      // Messages name the option or the file, echo the value short and say the rule.
      {"session", "query_min_sigma_zero", E::kCliUsage, "--min-sigma: must be a number > 0 and at most 1, got 0",
       then(write("pts.txt", "0 0 1\n"), "query {dir}/s.vdmap --op classify --min-sigma 0 --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_gate_sigma_huge", E::kCliUsage, "--gate-sigma: must be a number > 0 and at most 100, got 1e308",
       then(write("pts.txt", "0 0 1\n"), "query {dir}/s.vdmap --op classify --gate-sigma 1e308 --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_points_one_column", E::kCliError, "pts.txt:2: expected x y z (--op distance), got 1 field: '0'",
       then(write("pts.txt", "0 0 1  # a comment after the columns\n0\n"),
            "query {dir}/s.vdmap --op distance --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "render_view_file_camera_and_keyframe_view", E::kCliError,
       "v.json: 'camera' places the global view, but 'view' is 'keyframe:0'",
       then(viewFile([](nlohmann::json& j) {
              j["view"] = "keyframe:0";
              j["camera"] = {{"eye", {7, 1, 1}}, {"target", {0, 0, 0}}, {"up", {0, 0, 1}}, {"fov_y_deg", 60}};
            }),
            "render {dir}/s.vdmap --view-file {dir}/v.json --out {dir}/o.png")},
      {"session", "render_look_at_with_the_view_files_keyframe_view", E::kCliError,
       "--look-at places the global view's camera; {dir}/v.json's view 'keyframe:0' has its keyframe's",
       then(viewFile([](nlohmann::json& j) { j["view"] = "keyframe:0"; }),
            "render {dir}/s.vdmap --view-file {dir}/v.json --look-at 1,1,1,0,0,0 --out {dir}/o.png")},
      // A folder where a file is read, and paths the system cannot look up: the path and what is
      // wrong, never a library's exception text.
      {"session", "render_view_file_is_a_folder", E::kCliError, "v.json: is a folder, not a file",
       then(folderAt("v.json"),
            "render {dir}/s.vdmap --view-file {dir}/v.json --out {dir}/o.png")},
      {"session", "render_settings_is_a_folder", E::kCliError, "set.json: is a folder, not a file",
       then(folderAt("set.json"),
            "render {dir}/s.vdmap --settings {dir}/set.json --out {dir}/o.png")},
      {"session", "render_suite_is_a_folder", E::kCliError, "views.yaml: is a folder, not a file",
       then(folderAt("views.yaml"),
            "render --suite {dir}/views.yaml")},
      {"session", "query_keyframe_poses_is_a_folder", E::kCliError, "poses.txt: is a folder, not a file",
       then(
           [](const fs::path& d) {
             folderAt("poses.txt")(d);
             return write("pts.txt", "0 0 1\n")(d);
           },
            "query {dir}/s.vdmap --op classify --keyframe-poses {dir}/poses.txt --points {dir}/pts.txt --out {dir}/out.txt")},
      {"session", "query_points_is_a_folder", E::kCliError, "pts.txt: is a folder, not a file (--points)",
       then(folderAt("pts.txt"),
            "query {dir}/s.vdmap --op classify --points {dir}/pts.txt --out {dir}/out.txt")},
      {"trajectory", "is_a_folder", E::kInputError, "poses.txt: is a folder, not a file",
       folderAt("poses.txt")},
      {"ply_mesh", "is_a_folder", E::kInputError, "m.ply: is a folder, not a file",
       folderAt("m.ply")},
      {"camera_yaml", "is_a_folder", E::kInputError, "camera.yaml: is a folder, not a file",
       folderAt("camera.yaml")},
      {"session", "query_points_in_a_symlink_loop", E::kCliError, "loop/pts.txt: too many levels of symbolic links",
       then([](const fs::path& d) { fs::create_symlink("loop", d / "loop"); return std::string(); },
            "query {dir}/s.vdmap --op classify --points {dir}/loop/pts.txt --out {dir}/out.txt")},
      {"session", "render_out_name_too_long", E::kCliError, "aaaaaaaaaaaaaaaaaaaaa/o.png: file name too long",
       args("render {dir}/s.vdmap --out {dir}/" + std::string(300, 'a') + "/o.png")},
  };
  return all;
}

const Input& inputNamed(const std::string& name) {
  for (const Input& i : inputs())
    if (name == i.name) return i;
  throw std::logic_error("no input " + name);
}

// Copies the input's file in `dir` into its fuzzer's seed corpus as `name`; for a sequence folder,
// its lists, which are what fuzz_tum_list reads.
void addSeeds(const Input& input, const std::string& name, const fs::path& dir) {
  if (!input.fuzz_target) return;
  const fs::path corpus = fs::path(VDMAP_FUZZ_SEEDS) / input.fuzz_target;
  fs::create_directories(corpus);
  const fs::path file = dir / input.path;
  if (fs::is_regular_file(file)) writeText(corpus / name, readFile(file));
  for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt", "associations.txt"})
    if (fs::is_regular_file(file / list)) writeText(corpus / (name + "-" + list), readFile(file / list));
}

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.input << "/" << c.name; }

class BadInputMatrix : public testing::TestWithParam<BadCase> {};

TEST_P(BadInputMatrix, GivesTheExpectedErrorClass) {
  const BadCase& c = GetParam();
  const Input& input = inputNamed(c.input);
  test::TempDir dir;
  input.make_good(dir.path());
  const std::string arguments = c.damage(dir.path());
  addSeeds(input, std::string(c.input) + "-" + c.name, dir.path());

  if (c.expect == Expect::kCliError || c.expect == Expect::kCliUsage) {
    const test::RunResult r = test::runVdmap(replaceAll(arguments, "{dir}", dir.path().string()));
    ASSERT_NE(r.exit_code, 0) << r.out;
    EXPECT_NE(r.err.find(replaceAll(c.fragment, "{dir}", dir.path().string())), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << "a failed run leaves no output";
    EXPECT_EQ(r.err.rfind("vdmap", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(": error: "), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
    if (c.expect == Expect::kCliError) {
      EXPECT_EQ(r.exit_code, 1);
    } else {
      EXPECT_GE(r.exit_code, 100) << r.err;
      EXPECT_LE(r.exit_code, 114) << r.err;
      EXPECT_NE(r.err.find("(see --help)\n"), std::string::npos) << r.err;
    }
    return;
  }
  try {
    input.read(dir / input.path);
    FAIL() << "read without an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
  } catch (const std::exception& e) {
    FAIL() << "wrong error class (" << typeid(e).name() << "): " << e.what();
  }
}

std::string caseName(const testing::TestParamInfo<BadCase>& info) {
  return std::string(info.param.input) + "_" + info.param.name;
}

INSTANTIATE_TEST_SUITE_P(Inputs, BadInputMatrix, testing::ValuesIn(badCases()), caseName);

// The good input of every reader is read without error (the baseline each bad case damages),
// and is the first seed of its fuzzer.
TEST(BadInputMatrixBaseline, GoodInputsRead) {
  for (const Input& input : inputs()) {
    if (!input.read) continue;
    test::TempDir dir;
    input.make_good(dir.path());
    EXPECT_NO_THROW(input.read(dir / input.path)) << input.name;
    addSeeds(input, std::string(input.name) + "-good", dir.path());
  }
}

// A whole session shrunk to fit the fuzzers' 64 KiB input limit (scripts/fuzz -max_len): no
// images, a few keypoints and cells per keyframe. A real session is mostly image bytes, so cut to
// 64 KiB the fuzzer never reaches the keypoints, cells, edges or the tracked state; these can.
std::string compactSession(bool tracked) {
  MapperParams params;
  params.poses = tracked ? PoseSource::kTrack : PoseSource::kGroundTruth;
  const PinholeCamera camera{160, 120, 131.25, 131.25, 79.5, 59.5, 5000.0};
  Mapper mapper(camera, params);
  for (int i = 0; i < 66; ++i) mapper.addFrame(test::turningBoxRoomFrame(camera, i, 6.0));
  KeyframeGraph& graph = mapper.graph();
  for (std::size_t k = 0; k < graph.size(); ++k) {
    Keyframe& kf = graph.keyframe(static_cast<int>(k));
    kf.rgb_image = CompressedImage();
    kf.depth_image = CompressedImage();
    FrameFeatures& f = kf.features;
    const int keep = static_cast<int>(std::min<std::size_t>(f.size(), 4));
    f.keypoints.resize(keep);
    f.depth_m.resize(keep);
    f.descriptors = f.descriptors.rowRange(0, keep).clone();
    KeyframeContainer cells(kf.container.camera(), kf.container.cellSizePx());
    for (std::size_t c = 0; c < kf.container.size(); c += 97) {
      const StoredCell& cell = kf.container.cells()[c];
      cells.findOrCreate(cell.grid_index) = cell;
    }
    kf.container = std::move(cells);
    kf.frames_free.resize(std::min<std::size_t>(kf.frames_free.size(), 2));  // the section, not its bulk
  }
  return encodeSession(graph, sessionInfo(mapper, {}));
}

TEST(BadInputMatrixBaseline, CompactSessionsSeedTheFuzzerWhole) {
  const fs::path corpus = fs::path(VDMAP_FUZZ_SEEDS) / "session";
  fs::create_directories(corpus);
  for (const bool tracked : {false, true}) {
    const std::string bytes = compactSession(tracked);
    EXPECT_LE(bytes.size(), 65536u);
    const Session s = decodeSession(bytes, "compact.vdmap");
    EXPECT_GE(s.graph.size(), 3u);
    EXPECT_EQ(s.info.state.frame_poses.size(), 66u);
    if (tracked) {
      EXPECT_GE(s.info.state.pose_graph_edges.size(), 2u);
    }
    writeText(corpus / (tracked ? "session-compact-tracked" : "session-compact"), bytes);
  }
}

// A '#' after a record's columns starts a comment, as one at the start of a line does (it was
// read as more fields: "got 9 fields").
TEST(BadInputMatrixBaseline, ACommentAfterTheColumnsIsAComment) {
  test::TempDir dir;
  writeText(dir / "poses.txt", "0.5 1 2 3 0 0 0 1  # the first pose\n0.6 1 2 3 0 0 0 1\t#second\n");
  const auto poses = readTumTrajectory(dir / "poses.txt");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].t, 0.6);
}

TEST(BadInputMatrixBaseline, EveryInputHasBadCases) {
  for (const Input& input : inputs()) {
    int n = 0;
    for (const BadCase& c : badCases()) n += std::string(c.input) == input.name;
    EXPECT_GE(n, 1) << input.name;
  }
}

}  // namespace
}  // namespace vdmap
