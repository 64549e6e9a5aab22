// Gazebo SDF worlds through sdformat 12: tessellated primitives, meshes, polylines and heightmaps
// placed by their resolved poses, materials from custom elements, rules and defaults, and the
// <spherical_coordinates> origin.
#include <console_bridge/console.h>
#include <expat.h>
#include <jpeglib.h>
#include <png.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <exception>
#include <map>
#include <new>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <sdf/sdf.hh>
#include <set>
#include <sstream>

#include "backend.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::world {

namespace fs = std::filesystem;

// -------------------------------------------------------------------------------------------------
// SDF loading

namespace {

// sdformat writes its diagnostics to a process-wide console; the library must not print, so they
// are captured for the duration of a load and turned into errors or warnings. When a file is not
// valid SDF, sdformat also tries it as URDF, whose parser logs through console_bridge: those
// messages (about a missing <robot>) are dropped. One load at a time touches the consoles.
class ConsoleCapture {
 public:
  ConsoleCapture() : lock_(mutex()) {
    auto& stream = sdf::Console::Instance()->GetMsgStream();
    previous_ = stream.GetStream();
    stream.SetStream(&buffer_);
    console_bridge::useOutputHandler(&silent_);
  }
  ~ConsoleCapture() {
    console_bridge::restorePreviousOutputHandler();
    sdf::Console::Instance()->GetMsgStream().SetStream(previous_);
  }
  ConsoleCapture(const ConsoleCapture&) = delete;
  ConsoleCapture& operator=(const ConsoleCapture&) = delete;

  // Captured lines without terminal colour codes.
  [[nodiscard]] std::vector<std::string> lines() const {
    std::vector<std::string> out;
    std::istringstream in(buffer_.str());
    std::string line;
    while (std::getline(in, line)) {
      std::string clean;
      for (std::size_t i = 0; i < line.size(); ++i) {
        if (line[i] == '\x1b') {
          while (i < line.size() && line[i] != 'm') ++i;
          continue;
        }
        clean.push_back(line[i]);
      }
      if (clean.find_first_not_of(" \t") != std::string::npos) out.push_back(clean);
    }
    return out;
  }

 private:
  static std::mutex& mutex() {
    static std::mutex console_mutex;
    return console_mutex;
  }
  class Silent final : public console_bridge::OutputHandler {
   public:
    void log(const std::string& /*text*/, console_bridge::LogLevel /*level*/,
             const char* /*filename*/, int /*line*/) override {}
  };
  std::lock_guard<std::mutex> lock_;
  std::ostringstream buffer_;
  std::ostream* previous_ = nullptr;
  Silent silent_;
};

// A world-level <include> as written, for includes skytrace instantiates itself (see
// load_sdf_world: sdformat builds each unique included model once instead of once per include).
struct IncludeSpec {
  std::size_t begin = 0;  // byte range of the element in the file
  std::size_t end = 0;
  int line = 0;
  std::string uri;
  std::string name;
  std::optional<std::string> pose;  // six numbers relative to the world
  std::optional<bool> is_static;
  bool unusual =
      false;  // merge, placement_frame, a pose in another frame or format: left to sdformat
};

// What expat sees of the file before sdformat does: well-formedness (sdformat reports XML errors
// only on its console and would try the file as URDF), the root element, and the world-level
// includes with the names other elements refer to.
struct XmlScan {
  std::string text;
  std::string root;
  std::vector<IncludeSpec> includes;
  std::set<std::string> referenced_frames;  // relative_to / attached_to values
  bool world_joints = false;
  int worlds = 0;
  // expat's complaint ("file:line:column: malformed XML: ..."), empty when well-formed. sdformat's
  // parser (tinyxml2) is more lenient, so it decides; this message explains its failure.
  std::string xml_error;
};

Result<XmlScan> scan_xml(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, path.string() + ": cannot open the SDF file");
  std::ostringstream content;
  content << in.rdbuf();
  struct State {
    XmlScan scan;
    XML_Parser parser = nullptr;
    std::vector<std::string> stack;
    std::string characters;
  } state;
  state.scan.text = content.str();
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, decltype(&XML_ParserFree)> parser(
      XML_ParserCreate(nullptr), &XML_ParserFree);
  state.parser = parser.get();
  XML_SetUserData(parser.get(), &state);
  XML_SetElementHandler(
      parser.get(),
      [](void* data, const XML_Char* name, const XML_Char** attributes) {
        auto* st = static_cast<State*>(data);
        const std::string element(name);
        if (st->scan.root.empty()) st->scan.root = element;
        for (const XML_Char** a = attributes; *a != nullptr; a += 2) {
          const std::string key(a[0]);
          if (key == "relative_to" || key == "attached_to") st->scan.referenced_frames.insert(a[1]);
        }
        const std::size_t depth = st->stack.size();
        if (depth == 1 && element == "world") ++st->scan.worlds;
        if (depth == 2 && st->stack[1] == "world") {
          if (element == "include") {
            IncludeSpec include;
            include.begin = static_cast<std::size_t>(XML_GetCurrentByteIndex(st->parser));
            include.line = static_cast<int>(XML_GetCurrentLineNumber(st->parser));
            include.unusual = attributes[0] != nullptr;  // merge="true" and the like
            st->scan.includes.push_back(include);
          } else if (element == "joint") {
            st->scan.world_joints = true;
          }
        }
        if (depth == 3 && st->stack[2] == "include" && st->stack[1] == "world") {
          IncludeSpec& include = st->scan.includes.back();
          if (element == "pose") {
            for (const XML_Char** a = attributes; *a != nullptr; a += 2) {
              if (std::string(a[0]) != "relative_to" || std::string(a[1]) != "world")
                include.unusual = true;
            }
          } else if (element != "uri" && element != "name" && element != "static" &&
                     element != "plugin") {
            include.unusual = true;  // placement_frame, experimental parameters...
          }
        }
        st->stack.push_back(element);
        st->characters.clear();
      },
      [](void* data, const XML_Char* /*name*/) {
        auto* st = static_cast<State*>(data);
        const std::size_t depth = st->stack.size();
        if (depth == 4 && st->stack[2] == "include" && st->stack[1] == "world") {
          IncludeSpec& include = st->scan.includes.back();
          std::string value = st->characters;
          const auto first = value.find_first_not_of(" \t\r\n");
          const auto last = value.find_last_not_of(" \t\r\n");
          value =
              first == std::string::npos ? std::string() : value.substr(first, last - first + 1);
          const std::string& element = st->stack[3];
          if (element == "uri") include.uri = value;
          if (element == "name") include.name = value;
          if (element == "pose") include.pose = value;
          if (element == "static") {
            if (value == "true" || value == "1") {
              include.is_static = true;
            } else if (value == "false" || value == "0") {
              include.is_static = false;
            } else {
              include.unusual = true;
            }
          }
        }
        if (depth == 3 && st->stack[2] == "include" && st->stack[1] == "world") {
          st->scan.includes.back().end =
              static_cast<std::size_t>(XML_GetCurrentByteIndex(st->parser)) +
              static_cast<std::size_t>(XML_GetCurrentByteCount(st->parser));
        }
        st->stack.pop_back();
        st->characters.clear();
      });
  XML_SetCharacterDataHandler(parser.get(), [](void* data, const XML_Char* text, int length) {
    static_cast<State*>(data)->characters.append(text, static_cast<std::size_t>(length));
  });
  // "--" inside comments is not XML but tinyxml2 (sdformat) accepts it, and gz-sim's examples
  // use it: expat reads a copy with those blanked, same length so that offsets still match.
  std::string text = state.scan.text;
  for (std::size_t open = text.find("<!--"); open != std::string::npos;
       open = text.find("<!--", open + 4)) {
    const std::size_t close = text.find("-->", open + 4);
    const std::size_t stop = close == std::string::npos ? text.size() : close;
    for (std::size_t i = open + 4; i + 1 < stop; ++i) {
      if (text[i] == '-' && text[i + 1] == '-') text[i] = ' ';
    }
    if (close == std::string::npos) break;
    open = close;
  }
  if (XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), XML_TRUE) ==
      XML_STATUS_ERROR) {
    state.scan.xml_error = path.string() + ":" +
                           std::to_string(XML_GetCurrentLineNumber(parser.get())) + ":" +
                           std::to_string(XML_GetCurrentColumnNumber(parser.get())) +
                           ": malformed XML: " + XML_ErrorString(XML_GetErrorCode(parser.get()));
    state.scan.includes.clear();
    return std::move(state.scan);
  }
  if (state.scan.root != "sdf") {
    return make_error(ErrorCode::kParse, path.string() + ": not an SDF file (root element <" +
                                             state.scan.root + ">, expected <sdf>)");
  }
  return std::move(state.scan);
}

// Messages about the text given to sdformat name the world file instead of sdformat's placeholder.
std::string replace_string_source(std::string message, const fs::path& path) {
  const std::string placeholder = sdf::kSdfStringSource;
  for (std::size_t at = message.find(placeholder); at != std::string::npos;
       at = message.find(placeholder, at + path.string().size())) {
    message.replace(at, placeholder.size(), path.string());
  }
  return message;
}

std::optional<ignition::math::Pose3d> parse_pose(const std::string& text) {
  std::istringstream in(text);
  std::array<double, 6> v{};
  for (double& x : v) {
    if (!(in >> x) || !std::isfinite(x)) return std::nullopt;
  }
  std::string rest;
  if (in >> rest) return std::nullopt;
  return ignition::math::Pose3d(v[0], v[1], v[2], v[3], v[4], v[5]);
}

std::vector<fs::path> split_path_list(const char* value) {
  std::vector<fs::path> out;
  if (value == nullptr) return out;
  std::string list(value);
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = std::min(list.find(':', start), list.size());
    if (end > start) out.emplace_back(list.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

// model://, file:// and relative URIs to files, the way Gazebo searches them.
class Resolver {
 public:
  explicit Resolver(const SdfLoadOptions& options) {
    dirs_ = options.model_paths;
    if (options.use_environment_paths) {
      for (const char* variable :
           {"GAZEBO_MODEL_PATH", "GZ_SIM_RESOURCE_PATH", "IGN_GAZEBO_RESOURCE_PATH", "SDF_PATH"}) {
        for (auto& dir : split_path_list(std::getenv(variable))) dirs_.push_back(std::move(dir));
      }
    }
  }

  [[nodiscard]] const std::vector<fs::path>& dirs() const { return dirs_; }

  // The file or folder a URI names; nullopt when nothing exists. `base_dir` is the folder of the
  // SDF file that holds the URI (relative URIs are relative to it, as in SDF 1.7+).
  [[nodiscard]] std::optional<fs::path> resolve(const std::string& uri,
                                                const fs::path& base_dir) const {
    std::error_code ec;
    const auto exists = [&](const fs::path& p) { return fs::exists(p, ec); };
    if (uri.rfind("model://", 0) == 0) {
      const std::string rest = uri.substr(8);
      for (const auto& dir : dirs_) {
        if (exists(dir / rest)) return dir / rest;
      }
      return std::nullopt;
    }
    if (uri.rfind("http://", 0) == 0 || uri.rfind("https://", 0) == 0) return std::nullopt;
    std::string plain = uri.rfind("file://", 0) == 0 ? uri.substr(7) : uri;
    const fs::path p(plain);
    if (p.is_absolute()) return exists(p) ? std::optional<fs::path>(p) : std::nullopt;
    if (!base_dir.empty() && exists(base_dir / p)) return base_dir / p;
    for (const auto& dir : dirs_) {
      if (exists(dir / p)) return dir / p;
    }
    return std::nullopt;
  }

 private:
  std::vector<fs::path> dirs_;
};

// The SDF file a model folder holds: the first file model.config names in an <sdf> element that
// exists, else model.sdf.
std::optional<fs::path> model_file_of_folder(const fs::path& folder) {
  std::error_code ec;
  std::ifstream config(folder / "model.config", std::ios::binary);
  if (config) {
    std::ostringstream content;
    content << config.rdbuf();
    const std::string text = content.str();
    for (std::size_t at = text.find("<sdf"); at != std::string::npos; at = text.find("<sdf", at + 4)) {
      const std::size_t open_end = text.find('>', at);
      const std::size_t close = text.find("</sdf>", at);
      if (open_end == std::string::npos || close == std::string::npos || close < open_end) break;
      std::string name = text.substr(open_end + 1, close - open_end - 1);
      name.erase(0, name.find_first_not_of(" \t\r\n"));
      name.erase(name.find_last_not_of(" \t\r\n") + 1);
      if (!name.empty() && fs::is_regular_file(folder / name, ec)) return folder / name;
    }
  }
  if (fs::is_regular_file(folder / "model.sdf", ec)) return folder / "model.sdf";
  return std::nullopt;
}

// Follows every <include> URI from the world file through the model files it reaches, before
// sdformat does: sdformat expands includes recursively without a limit, so a file that includes
// itself (directly or through others) would take all memory. Reports the first cycle or a chain
// deeper than kMaxIncludeDepth with the file and line of each step.
class IncludeGraphCheck {
 public:
  static constexpr int kMaxIncludeDepth = 32;
  static constexpr std::size_t kMaxFiles = 20000;

  explicit IncludeGraphCheck(const Resolver& resolver) : resolver_(resolver) {}

  Status check(const fs::path& file) { return visit(file, 0); }

 private:
  struct Uri {
    std::string text;
    int line = 0;
  };

  // <uri> values inside <include> elements (comments skipped), with their lines.
  static std::vector<Uri> include_uris(const std::string& text) {
    std::vector<Uri> out;
    int line = 1;
    std::size_t counted = 0;
    const auto line_at = [&](std::size_t position) {
      line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(counted),
                                          text.begin() + static_cast<std::ptrdiff_t>(position), '\n'));
      counted = position;
      return line;
    };
    int include_depth = 0;
    for (std::size_t at = text.find('<'); at != std::string::npos; at = text.find('<', at + 1)) {
      if (text.compare(at, 4, "<!--") == 0) {
        const std::size_t end = text.find("-->", at + 4);
        if (end == std::string::npos) break;
        at = end;
        continue;
      }
      if (text.compare(at, 8, "<include") == 0 && (at + 8 < text.size()) &&
          (text[at + 8] == '>' || std::isspace(static_cast<unsigned char>(text[at + 8])))) {
        const std::size_t end = text.find('>', at);
        if (end != std::string::npos && text[end - 1] != '/') ++include_depth;
      } else if (text.compare(at, 10, "</include>") == 0) {
        include_depth = std::max(0, include_depth - 1);
      } else if (include_depth > 0 && text.compare(at, 5, "<uri>") == 0) {
        const std::size_t close = text.find("</uri>", at + 5);
        if (close == std::string::npos) break;
        std::string value = text.substr(at + 5, close - at - 5);
        value.erase(0, value.find_first_not_of(" \t\r\n"));
        value.erase(value.find_last_not_of(" \t\r\n") + 1);
        out.push_back({value, line_at(at)});
      }
    }
    return out;
  }

  Status visit(const fs::path& file, int depth) {
    std::error_code ec;
    const fs::path key = fs::weakly_canonical(file, ec);
    if (done_.count(key) != 0) return Ok{};
    if (done_.size() > kMaxFiles) {
      return make_error(ErrorCode::kParse, file.string() + ": includes reach more than 20000 model files");
    }
    std::ifstream in(file, std::ios::binary);
    if (!in) return Ok{};  // unreadable files are reported by the load itself
    std::ostringstream content;
    content << in.rdbuf();
    chain_.push_back(key);
    for (const Uri& uri : include_uris(content.str())) {
      const auto resolved = resolver_.resolve(uri.text, file.parent_path());
      if (!resolved) continue;  // a missing model is a warning of the load
      std::optional<fs::path> target = *resolved;
      if (fs::is_directory(*resolved, ec)) target = model_file_of_folder(*resolved);
      if (!target) continue;
      const std::string place = file.string() + ":" + std::to_string(uri.line);
      const fs::path target_key = fs::weakly_canonical(*target, ec);
      if (std::find(chain_.begin(), chain_.end(), target_key) != chain_.end()) {
        std::string cycle;
        for (auto it = std::find(chain_.begin(), chain_.end(), target_key); it != chain_.end(); ++it) {
          cycle += it->string() + " -> ";
        }
        return make_error(ErrorCode::kParse, place + ": <include> of '" + uri.text + "' closes a cycle (" + cycle +
                                                 target_key.string() + "): a world or model cannot include itself");
      }
      if (depth + 1 >= kMaxIncludeDepth) {
        return make_error(ErrorCode::kParse, place + ": includes nested deeper than " +
                                                 std::to_string(kMaxIncludeDepth) + " levels");
      }
      if (auto st = visit(*target, depth + 1); !st) return st;
    }
    chain_.pop_back();
    done_.insert(key);
    return Ok{};
  }

  const Resolver& resolver_;
  std::vector<fs::path> chain_;
  std::set<fs::path> done_;
};

Eigen::Isometry3d to_isometry(const ignition::math::Pose3d& pose) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.translation() = Eigen::Vector3d(pose.Pos().X(), pose.Pos().Y(), pose.Pos().Z());
  const auto& q = pose.Rot();
  out.linear() = Eigen::Quaterniond(q.W(), q.X(), q.Y(), q.Z()).normalized().toRotationMatrix();
  return out;
}

std::string where(const sdf::ElementPtr& element) {
  if (!element) return "";
  // Elements parsed from text (see load_sdf_world) have no file: the placeholder is replaced by the
  // world's path in the messages.
  std::string out =
      element->FilePath().empty() ? std::string(sdf::kSdfStringSource) : element->FilePath();
  // Appends rather than "a" + b: GCC 12 warns falsely (-Wrestrict) on the latter here.
  if (const auto line = element->LineNumber()) out.append(":").append(std::to_string(*line));
  return out;
}

std::string error_text(const sdf::Error& error) {
  std::string out;
  if (error.FilePath()) out += *error.FilePath();
  if (error.LineNumber()) out.append(":").append(std::to_string(*error.LineNumber()));
  if (!out.empty()) out.append(": ");
  return out.append(error.Message());
}

// SDFormat needs unique model names among siblings; worlds saved by Gazebo classic (PX4's test
// cities) repeat them. Later copies get "_2", "_3"... so that every copy is loaded.
void rename_duplicate_models(const sdf::ElementPtr& parent, std::vector<std::string>& warnings) {
  std::map<std::string, int> count;
  std::set<std::string> taken;
  for (auto child = parent->GetFirstElement(); child; child = child->GetNextElement()) {
    if (child->HasAttribute("name")) taken.insert(child->GetAttribute("name")->GetAsString());
  }
  std::map<std::string, int> renamed;
  for (auto model = parent->GetFirstElement(); model; model = model->GetNextElement()) {
    if (model->GetName() == "model") {
      const std::string name = model->GetAttribute("name")->GetAsString();
      if (++count[name] > 1) {
        int suffix = count[name];
        while (taken.count(name + "_" + std::to_string(suffix)) != 0) ++suffix;
        const std::string fresh = name + "_" + std::to_string(suffix);
        model->GetAttribute("name")->SetFromString(fresh);
        taken.insert(fresh);
        ++renamed[name];
      }
      rename_duplicate_models(model, warnings);
    }
  }
  for (const auto& [name, copies] : renamed) {
    warnings.push_back(
        where(parent) + ": " + std::to_string(copies + 1) + " models named '" + name +
        "' (SDFormat needs unique names, Gazebo classic accepted them): copies renamed '" + name +
        "_2'...");
  }
}

// Gazebo classic restores the model poses saved in a world's <state>; so do we, for top-level
// models with unique names.
std::map<std::string, ignition::math::Pose3d> state_poses(const sdf::ElementPtr& world) {
  std::map<std::string, ignition::math::Pose3d> poses;
  for (auto state = world->GetElementImpl("state"); state; state = state->GetNextElement("state")) {
    for (auto model = state->GetElementImpl("model"); model;
         model = model->GetNextElement("model")) {
      if (model->HasElement("pose") && model->HasAttribute("name")) {
        poses[model->GetAttribute("name")->GetAsString()] =
            model->GetElementImpl("pose")->Get<ignition::math::Pose3d>();
      }
    }
  }
  return poses;
}

// --- heightmap images
// -----------------------------------------------------------------------------

struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<double> values;  // [0, 1], row 0 at the top
};

struct JpegErrorManager {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

// libjpeg reports fatal errors through longjmp; the buffers live outside the jump's reach.
bool decode_jpeg(std::FILE* file, jpeg_decompress_struct& info, JpegErrorManager& errors,
                 std::vector<unsigned char>& pixels, int& width, int& height) {
  info.err = jpeg_std_error(&errors.manager);
  errors.manager.error_exit = [](j_common_ptr common) {
    auto* manager = reinterpret_cast<JpegErrorManager*>(common->err);
    (*common->err->format_message)(common, manager->message);
    std::longjmp(manager->jump, 1);
  };
  if (setjmp(errors.jump) != 0) {
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  jpeg_stdio_src(&info, file);
  jpeg_read_header(&info, TRUE);
  info.out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(&info);
  width = static_cast<int>(info.output_width);
  height = static_cast<int>(info.output_height);
  pixels.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = pixels.data() +
                   static_cast<std::size_t>(info.output_scanline) * static_cast<std::size_t>(width);
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

Result<GrayImage> read_gray_image(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  GrayImage image;
  if (extension == ".png") {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_file(&png, path.string().c_str()) == 0) {
      return make_error(ErrorCode::kParse,
                        path.string() + ": cannot read the PNG image: " + png.message);
    }
    // 16-bit images (DEM-like heightmaps) keep their 16 bits; 8-bit ones are read as 8-bit gray.
    const bool sixteen = (png.format & PNG_FORMAT_FLAG_LINEAR) != 0;
    png.format = sixteen ? PNG_FORMAT_LINEAR_Y : PNG_FORMAT_GRAY;
    image.width = static_cast<int>(png.width);
    image.height = static_cast<int>(png.height);
    const std::size_t count = static_cast<std::size_t>(png.width) * png.height;
    if (sixteen) {
      std::vector<png_uint_16> pixels(count);
      if (png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr) == 0) {
        return make_error(ErrorCode::kParse,
                          path.string() + ": cannot decode the PNG image: " + png.message);
      }
      for (const auto v : pixels) image.values.push_back(v / 65535.0);
    } else {
      std::vector<png_byte> pixels(count);
      if (png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr) == 0) {
        return make_error(ErrorCode::kParse,
                          path.string() + ": cannot decode the PNG image: " + png.message);
      }
      for (const auto v : pixels) image.values.push_back(v / 255.0);
    }
    return image;
  }
  if (extension == ".jpg" || extension == ".jpeg") {
    std::unique_ptr<std::FILE, decltype(&std::fclose)> file(std::fopen(path.string().c_str(), "rb"),
                                                            &std::fclose);
    if (!file) return make_error(ErrorCode::kIo, path.string() + ": cannot open the JPEG image");
    jpeg_decompress_struct info{};
    JpegErrorManager errors{};
    std::vector<unsigned char> pixels;
    if (!decode_jpeg(file.get(), info, errors, pixels, image.width, image.height)) {
      return make_error(ErrorCode::kParse,
                        path.string() + ": cannot decode the JPEG image: " + errors.message);
    }
    for (const auto v : pixels) image.values.push_back(v / 255.0);
    return image;
  }
  return make_error(
      ErrorCode::kUnsupported,
      path.string() +
          ": heightmap format not supported (PNG and JPEG images only; DEM files are not)");
}

// --- the walk
// ---------------------------------------------------------------------------------------

struct MeshEntry {
  Result<TriangleMesh> mesh = TriangleMesh{};
  std::optional<Result<TriangleMesh>> hull;
  std::map<double, TriangleMesh> simplified_hulls;  // by tolerance in the mesh's own units
};

// What an object inherits from its enclosing models.
struct Chain {
  std::vector<std::string> names;  // outer to inner
  std::vector<std::string>
      uris;  // model:// identity of each model (include URI or model folder), may be empty
  std::vector<sdf::ElementPtr> elements;
  bool is_static = false;
};

struct Geometry {
  std::string name;
  sdf::ElementPtr element;  // the <collision> or <visual>
  const sdf::Geometry* geometry = nullptr;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // in the link frame
};

struct BuiltShape {
  TriangleMesh mesh;
  bool is_ground = false;  // plane or heightmap
  bool is_closed =
      true;  // primitives and prisms are volumes; meshes, planes and heightmaps may not be
  std::string mesh_uri;
  std::string submesh;
  // Meshes: the cached file and the instance's scale, to build the vegetation hull once per file.
  std::shared_ptr<MeshEntry> mesh_entry;
  Eigen::Vector3f scale = Eigen::Vector3f::Ones();
};

BuiltShape solid(TriangleMesh mesh) {
  BuiltShape shape;
  shape.mesh = std::move(mesh);
  return shape;
}

class SdfWalker {
 public:
  SdfWalker(const SdfLoadOptions& options, const Resolver& resolver, WorldModel& world,
            fs::path world_file)
      : options_(options), resolver_(resolver), world_(world), world_file_(std::move(world_file)) {}

  // What an <include> changes in the model it brings in.
  struct Overrides {
    std::string name;
    std::string uri;
    std::optional<bool> is_static;
  };

  void model(const sdf::Model& model, const Eigen::Isometry3d& world_from_model, Chain chain,
             const Overrides& overrides = {}) {
    if (chain.names.empty()) {
      world_.model_poses[overrides.name.empty() ? model.Name() : overrides.name] = world_from_model;
    }
    chain.names.push_back(overrides.name.empty() ? model.Name() : overrides.name);
    chain.uris.push_back(overrides.uri.empty() ? model_identity(model.Element()) : overrides.uri);
    chain.elements.push_back(model.Element());
    chain.is_static = chain.is_static || overrides.is_static.value_or(model.Static());
    const std::size_t first_object = world_.objects.size();

    for (uint64_t l = 0; l < model.LinkCount(); ++l) {
      const sdf::Link* link = model.LinkByIndex(l);
      ignition::math::Pose3d link_pose;
      const auto errors = link->SemanticPose().Resolve(link_pose);
      if (!errors.empty()) {
        warn(where(link->Element()) + ": link " + join(chain.names) + "/" + link->Name() +
             " skipped, its pose cannot be resolved: " + error_text(errors.front()));
        continue;
      }
      const Eigen::Isometry3d world_from_link = world_from_model * to_isometry(link_pose);
      for (const Geometry& geometry : geometries(*link)) {
        const std::string object_name =
            join(chain.names) + "/" + link->Name() + "/" + geometry.name;
        auto shapes = build(geometry, object_name);
        for (auto& shape : shapes) {
          WorldObject object;
          object.name = object_name;
          object.pose = world_from_link * geometry.pose;
          object.is_static = chain.is_static;
          object.mesh = std::move(shape.mesh);
          if (!assign_material(object, chain, *link, geometry, shape)) continue;
          world_.objects.push_back(std::move(object));
        }
      }
    }
    classify_buildings(first_object, chain);

    for (uint64_t n = 0; n < model.ModelCount(); ++n) {
      const sdf::Model* nested = model.ModelByIndex(n);
      ignition::math::Pose3d nested_pose;
      const auto errors = nested->SemanticPose().Resolve(nested_pose);
      if (!errors.empty()) {
        warn(where(nested->Element()) + ": model " + join(chain.names) + "/" + nested->Name() +
             " skipped, its pose cannot be resolved: " + error_text(errors.front()));
        continue;
      }
      this->model(*nested, world_from_model * to_isometry(nested_pose), chain);
    }
  }

  void finish() {
    for (const auto& [uri, info] : missing_meshes_) {
      warn(info.first + ": mesh " + uri + " not found, " + std::to_string(info.second) +
           " geometr" + (info.second == 1 ? "y" : "ies") + " skipped" + search_note());
    }
  }

  // The first mesh that exists but could not be read (see SdfLoadOptions::unreadable_mesh_is_error).
  [[nodiscard]] const std::optional<std::string>& unreadable_mesh() const { return unreadable_mesh_; }

  [[nodiscard]] std::string search_note() const {
    std::string note = " (searched: ";
    if (resolver_.dirs().empty()) return note + "no model paths)";
    for (std::size_t i = 0; i < resolver_.dirs().size(); ++i)
      note += (i > 0 ? ", " : "") + resolver_.dirs()[i].string();
    return note + ")";
  }

 private:
  static std::string join(const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : "/") + n;
    return out;
  }

  void warn(std::string message) { world_.warnings.push_back(std::move(message)); }

  // The model:// URI the model came from (its <include>), or "model://<folder>" of its file when it
  // comes from another file than the world.
  std::string model_identity(const sdf::ElementPtr& element) const {
    if (!element) return "";
    if (const auto include = element->GetIncludeElement(); include && include->HasElement("uri")) {
      return include->GetElementImpl("uri")->Get<std::string>();
    }
    const fs::path file(element->FilePath());
    if (!file.empty() && file != world_file_ && element->FilePath() != sdf::kSdfStringSource) {
      return "model://" + file.parent_path().filename().string();
    }
    return "";
  }

  std::vector<Geometry> geometries(const sdf::Link& link) const {
    std::vector<Geometry> out;
    const bool collisions = options_.geometry != GeometrySource::kVisual;
    if (collisions) {
      for (uint64_t c = 0; c < link.CollisionCount(); ++c) {
        const sdf::Collision* collision = link.CollisionByIndex(c);
        out.push_back({collision->Name(), collision->Element(), collision->Geom(),
                       pose_of(collision->SemanticPose())});
      }
    }
    if (options_.geometry == GeometrySource::kVisual ||
        (options_.geometry == GeometrySource::kCollisionElseVisual && link.CollisionCount() == 0)) {
      for (uint64_t v = 0; v < link.VisualCount(); ++v) {
        const sdf::Visual* visual = link.VisualByIndex(v);
        out.push_back(
            {visual->Name(), visual->Element(), visual->Geom(), pose_of(visual->SemanticPose())});
      }
    }
    return out;
  }

  static Eigen::Isometry3d pose_of(const sdf::SemanticPose& semantic) {
    ignition::math::Pose3d pose;
    // Collisions and visuals resolve relative to their link; an unresolvable frame was already
    // reported by sdformat as an error, which stops the load.
    (void)semantic.Resolve(pose);
    return to_isometry(pose);
  }

  std::vector<BuiltShape> build(const Geometry& geometry, const std::string& object_name) {
    std::vector<BuiltShape> out;
    const sdf::Geometry& g = *geometry.geometry;
    const int segments = options_.round_segments;
    const int rings = options_.round_rings;
    switch (g.Type()) {
      case sdf::GeometryType::BOX: {
        const auto s = g.BoxShape()->Size();
        out.push_back(solid(make_box({s.X(), s.Y(), s.Z()})));
        break;
      }
      case sdf::GeometryType::CYLINDER:
        out.push_back(solid(
            make_cylinder(g.CylinderShape()->Radius(), g.CylinderShape()->Length(), segments)));
        break;
      case sdf::GeometryType::SPHERE: {
        const double r = g.SphereShape()->Radius();
        out.push_back(solid(make_ellipsoid({r, r, r}, segments, rings)));
        break;
      }
      case sdf::GeometryType::CAPSULE:
        out.push_back(solid(
            make_capsule(g.CapsuleShape()->Radius(), g.CapsuleShape()->Length(), segments, rings)));
        break;
      case sdf::GeometryType::ELLIPSOID: {
        const auto r = g.EllipsoidShape()->Radii();
        out.push_back(solid(make_ellipsoid({r.X(), r.Y(), r.Z()}, segments, rings)));
        break;
      }
      case sdf::GeometryType::PLANE: {
        const sdf::Plane* plane = g.PlaneShape();
        const auto n = plane->Normal();
        Eigen::Vector2d size(plane->Size().X(), plane->Size().Y());
        const auto size_element =
            plane->Element() ? plane->Element()->GetElementImpl("size") : nullptr;
        if (!size_element || !size_element->GetValue() || !size_element->GetValue()->GetSet()) {
          size = Eigen::Vector2d::Constant(
              options_.infinite_plane_size_m);  // Gazebo's plane is infinite
        }
        BuiltShape shape = solid(make_plane({n.X(), n.Y(), n.Z()}, size));
        shape.is_ground = true;
        shape.is_closed = false;
        out.push_back(std::move(shape));
        break;
      }
      case sdf::GeometryType::MESH: {
        if (auto shape = mesh(*g.MeshShape(), object_name)) out.push_back(std::move(*shape));
        break;
      }
      case sdf::GeometryType::HEIGHTMAP: {
        if (auto shape = heightmap(*g.HeightmapShape(), object_name))
          out.push_back(std::move(*shape));
        break;
      }
      case sdf::GeometryType::EMPTY:
      default: {
        const sdf::ElementPtr element = g.Element();
        if (element && element->HasElement("polyline")) {
          polylines(element, object_name, out);
        } else if (element && element->HasElement("image")) {
          warn(where(geometry.element) + ": " + object_name +
               ": <image> geometry skipped (not supported)");
        }
        break;
      }
    }
    return out;
  }

  // The folder relative URIs start from: the file the element came from.
  fs::path base_dir(const std::string& file_path) const {
    return file_path.empty() || file_path == sdf::kSdfStringSource
               ? world_file_.parent_path()
               : fs::path(file_path).parent_path();
  }

  std::optional<BuiltShape> mesh(const sdf::Mesh& mesh, const std::string& object_name) {
    const fs::path base = base_dir(mesh.FilePath());
    const std::string uri = mesh.Uri();
    const auto resolved = resolver_.resolve(uri, base);
    if (!resolved) {
      auto& entry = missing_meshes_[uri];
      if (entry.second++ == 0) entry.first = where(mesh.Element()) + ": " + object_name;
      return std::nullopt;
    }
    const std::string key =
        resolved->string() + "|" + mesh.Submesh() + "|" + (mesh.CenterSubmesh() ? "c" : "");
    auto& entry = mesh_cache_[key];
    if (!entry) {
      entry = std::make_shared<MeshEntry>();
      entry->mesh = read_selected(*resolved, mesh.Submesh(), mesh.CenterSubmesh());
    }
    if (!entry->mesh.ok()) {
      const std::string what = where(mesh.Element()) + ": " + object_name;
      if (options_.unreadable_mesh_is_error) {
        if (!unreadable_mesh_) unreadable_mesh_ = what + ": " + entry->mesh.error().message;
      } else {
        warn(what + " skipped: " + entry->mesh.error().message);
      }
      return std::nullopt;
    }
    const auto s = mesh.Scale();
    const Eigen::Vector3f scale(static_cast<float>(s.X()), static_cast<float>(s.Y()),
                                static_cast<float>(s.Z()));
    if (!(scale.array().abs() > 0.0F).all() || !scale.allFinite()) {
      warn(where(mesh.Element()) + ": " + object_name +
           " skipped: mesh scale has a zero component");
      return std::nullopt;
    }
    BuiltShape shape;
    shape.mesh = *entry->mesh;
    shape.is_closed = false;
    shape.mesh_uri = uri;
    shape.submesh = mesh.Submesh();
    scale_mesh(shape.mesh, scale);
    shape.mesh_entry = entry;
    shape.scale = scale;
    return shape;
  }

  static void scale_mesh(TriangleMesh& mesh, const Eigen::Vector3f& scale) {
    for (auto& v : mesh.vertices_m) v = v.cwiseProduct(scale);
    if (scale.x() * scale.y() * scale.z() < 0.0F) {  // a mirror flips the winding
      for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    }
  }

  static Result<TriangleMesh> read_selected(const fs::path& path, const std::string& submesh,
                                            bool center) {
    auto parts = read_mesh_file(path);
    if (!parts.ok()) return parts.error();
    TriangleMesh merged;
    for (const auto& part : *parts) {
      if (!submesh.empty() && part.node_name != submesh && part.mesh_name != submesh) continue;
      const int base = static_cast<int>(merged.vertices_m.size());
      merged.vertices_m.insert(merged.vertices_m.end(), part.mesh.vertices_m.begin(),
                               part.mesh.vertices_m.end());
      for (const auto& t : part.mesh.triangles)
        merged.triangles.push_back(t + Eigen::Vector3i::Constant(base));
    }
    if (merged.triangles.empty()) {
      return make_error(ErrorCode::kNotFound,
                        path.string() + ": no submesh named '" + submesh + "'");
    }
    if (center && !submesh.empty()) {
      // Gazebo's <center>: the submesh's bounding box centre moves to the origin.
      Eigen::Vector3f low = merged.vertices_m.front();
      Eigen::Vector3f high = low;
      for (const auto& v : merged.vertices_m) {
        low = low.cwiseMin(v);
        high = high.cwiseMax(v);
      }
      const Eigen::Vector3f middle = 0.5F * (low + high);
      for (auto& v : merged.vertices_m) v -= middle;
    }
    return merged;
  }

  std::optional<BuiltShape> heightmap(const sdf::Heightmap& heightmap,
                                      const std::string& object_name) {
    const fs::path base = base_dir(heightmap.FilePath());
    const auto resolved = resolver_.resolve(heightmap.Uri(), base);
    if (!resolved) {
      warn(where(heightmap.Element()) + ": " + object_name + ": heightmap " + heightmap.Uri() +
           " not found, skipped" + search_note());
      return std::nullopt;
    }
    auto image = read_gray_image(*resolved);
    if (!image.ok()) {
      warn(where(heightmap.Element()) + ": " + object_name +
           ": heightmap skipped: " + image.error().message);
      return std::nullopt;
    }
    const auto size = heightmap.Size();
    const auto position = heightmap.Position();
    std::vector<double> heights_m;
    heights_m.reserve(image->values.size());
    // Gazebo: brightness 0..1 maps to 0..size.z above the heightmap's position.
    for (const double v : image->values) heights_m.push_back(position.Z() + v * size.Z());
    auto grid = make_height_grid(heights_m, image->height, image->width, size.X(), size.Y());
    if (!grid.ok()) {
      warn(where(heightmap.Element()) + ": " + object_name +
           ": heightmap skipped: " + grid.error().message);
      return std::nullopt;
    }
    for (auto& v : grid->vertices_m) {
      v.x() += static_cast<float>(position.X());
      v.y() += static_cast<float>(position.Y());
    }
    BuiltShape shape;
    shape.mesh = std::move(*grid);
    shape.is_ground = true;
    shape.is_closed = false;
    return shape;
  }

  // <polyline>: the first is the outline, later ones inside it are holes, others separate prisms;
  // all extruded from z = 0 up to their height, as Gazebo does.
  void polylines(const sdf::ElementPtr& geometry, const std::string& object_name,
                 std::vector<BuiltShape>& out) {
    struct Line {
      Ring2 points;
      double height_m = 0.0;
    };
    std::vector<Line> lines;
    for (auto polyline = geometry->GetElementImpl("polyline"); polyline;
         polyline = polyline->GetNextElement("polyline")) {
      Line line;
      line.height_m =
          polyline->HasElement("height") ? polyline->GetElementImpl("height")->Get<double>() : 1.0;
      for (auto point = polyline->GetElementImpl("point"); point;
           point = point->GetNextElement("point")) {
        const auto p = point->Get<ignition::math::Vector2d>();
        line.points.emplace_back(p.X(), p.Y());
      }
      lines.push_back(std::move(line));
    }
    if (lines.empty()) return;
    const auto inside = [](const Ring2& ring, const Eigen::Vector2d& p) {
      bool in = false;
      for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
        if ((ring[i].y() > p.y()) != (ring[j].y() > p.y()) &&
            p.x() <
                (ring[j].x() - ring[i].x()) * (p.y() - ring[i].y()) / (ring[j].y() - ring[i].y()) +
                    ring[i].x()) {
          in = !in;
        }
      }
      return in;
    };
    PolygonWithHoles first{lines.front().points, {}};
    std::vector<const Line*> separate;
    for (std::size_t i = 1; i < lines.size(); ++i) {
      if (!lines[i].points.empty() && inside(first.outer, lines[i].points.front())) {
        first.holes.push_back(lines[i].points);
      } else {
        separate.push_back(&lines[i]);
      }
    }
    const auto add = [&](const PolygonWithHoles& polygon, double height_m) {
      auto prism = extrude_polygon(polygon, 0.0, height_m);
      if (!prism.ok()) {
        warn(where(geometry) + ": " + object_name + ": polyline skipped: " + prism.error().message);
        return;
      }
      out.push_back(solid(std::move(*prism)));
    };
    add(first, lines.front().height_m);
    for (const Line* line : separate) add(PolygonWithHoles{line->points, {}}, line->height_m);
  }

  // Reads <skytrace:material class="..." attenuation_db_per_m="..." kind="..."/> or
  // <skytrace:vegetation attenuation_db_per_m="..."/> directly under `element`.
  struct CustomMaterial {
    Material material;
    std::optional<ObjectKind> kind;
  };
  std::optional<CustomMaterial> custom_material(const sdf::ElementPtr& element,
                                                const std::string& object_name) {
    if (!element) return std::nullopt;
    const auto attribute = [](const sdf::ElementPtr& e,
                              const std::string& key) -> std::optional<std::string> {
      if (!e->HasAttribute(key)) return std::nullopt;
      return e->GetAttribute(key)->GetAsString();
    };
    const auto attenuation = [&](const sdf::ElementPtr& e, double fallback) {
      const auto text = attribute(e, "attenuation_db_per_m");
      if (!text) return fallback;
      char* end = nullptr;
      const double value = std::strtod(text->c_str(), &end);
      if (end == text->c_str() || *end != '\0' || !(value >= 0.0) || !std::isfinite(value)) {
        warn(where(element) + ": " + object_name + ": attenuation_db_per_m='" + *text +
             "' is not a non-negative number, " + std::to_string(fallback) + " dB/m used");
        return fallback;
      }
      return value;
    };
    if (const auto vegetation = element->FindElement("skytrace:vegetation")) {
      return CustomMaterial{
          Material{MaterialClass::kVegetation,
                   attenuation(vegetation, options_.vegetation_attenuation_db_per_m)},
          ObjectKind::kTree};
    }
    const auto custom = element->FindElement("skytrace:material");
    if (!custom) return std::nullopt;
    CustomMaterial out;
    if (const auto name = attribute(custom, "class")) {
      auto parsed = parse_material_class(*name);
      if (!parsed.ok()) {
        warn(where(element) + ": " + object_name +
             ": <skytrace:material> ignored: " + parsed.error().message);
        return std::nullopt;
      }
      out.material.material_class = *parsed;
    } else {
      warn(where(element) + ": " + object_name +
           ": <skytrace:material> without a class attribute ignored");
      return std::nullopt;
    }
    if (out.material.is_vegetation()) {
      out.material.attenuation_db_per_m =
          attenuation(custom, options_.vegetation_attenuation_db_per_m);
    }
    if (const auto kind = attribute(custom, "kind")) {
      for (const ObjectKind k :
           {ObjectKind::kBuilding, ObjectKind::kTree, ObjectKind::kGround, ObjectKind::kOther}) {
        if (object_kind_name(k) == *kind) out.kind = k;
      }
      if (!out.kind)
        warn(where(element) + ": " + object_name + ": kind='" + *kind +
             "' ignored (building, tree, ground, other)");
    }
    return out;
  }

  // Scenario rules, then custom elements (collision, link, models inner to outer), then defaults.
  // Returns false when the object must be dropped (vegetation without a volume).
  bool assign_material(WorldObject& object, const Chain& chain, const sdf::Link& link,
                       const Geometry& geometry, BuiltShape& shape) {
    std::vector<std::string> names = {object.name};
    names.insert(names.end(), chain.names.begin(), chain.names.end());
    names.insert(names.end(), chain.uris.begin(), chain.uris.end());
    if (!shape.mesh_uri.empty()) names.push_back(shape.mesh_uri);
    if (!shape.submesh.empty()) names.push_back(shape.submesh);

    std::optional<ObjectKind> kind;
    bool decided = false;
    if (const MaterialRule* rule = match_material_rule(options_.material_rules, names)) {
      object.material = rule->material;
      kind = rule->kind;
      decided = true;
    }
    if (!decided) {
      std::vector<sdf::ElementPtr> carriers = {geometry.element, link.Element()};
      carriers.insert(carriers.end(), chain.elements.rbegin(), chain.elements.rend());
      for (const auto& carrier : carriers) {
        if (auto custom = custom_material(carrier, object.name)) {
          object.material = custom->material;
          kind = custom->kind;
          decided = true;
          break;
        }
      }
    }
    if (!decided) {
      const bool vegetation =
          std::any_of(chain.names.begin(), chain.names.end(), name_suggests_vegetation) ||
          std::any_of(chain.uris.begin(), chain.uris.end(), name_suggests_vegetation) ||
          name_suggests_vegetation(shape.mesh_uri) || name_suggests_vegetation(shape.submesh);
      if (shape.is_ground) {
        object.material = Material{MaterialClass::kGround, 0.0};
      } else if (vegetation) {
        object.material =
            Material{MaterialClass::kVegetation, options_.vegetation_attenuation_db_per_m};
      } else {
        object.material = Material{MaterialClass::kConcrete, 0.0};
      }
    }
    if (object.material.is_vegetation() && shape.is_ground) {
      warn(object.name +
           ": a plane or heightmap cannot be vegetation (no volume), kept as opaque ground");
      object.material = Material{MaterialClass::kGround, 0.0};
    }
    if (object.material.is_vegetation() && !shape.is_closed && options_.vegetation_convex_hull) {
      if (!make_vegetation_volume(object, shape)) return false;
    }
    if (kind) {
      object.kind = *kind;
    } else if (object.material.is_vegetation()) {
      object.kind = ObjectKind::kTree;
    } else if (shape.is_ground || object.material.material_class == MaterialClass::kGround) {
      object.kind = ObjectKind::kGround;
    } else {
      object.kind = ObjectKind::kOther;  // buildings are decided per model in classify_buildings
      unclassified_.insert(world_.objects.size());
    }
    return true;
  }

  // The convex hull of the (scaled) mesh: hulls commute with scaling, so the hull of the unscaled
  // mesh is computed once per mesh file and scaled per instance.
  bool make_vegetation_volume(WorldObject& object, const BuiltShape& shape) {
    if (shape.mesh_entry == nullptr) return true;
    auto& entry = *shape.mesh_entry;
    if (!entry.hull) entry.hull = convex_hull(entry.mesh->vertices_m);
    if (!entry.hull->ok()) {
      warn(object.name +
           ": vegetation skipped, its mesh has no volume: " + entry.hull->error().message);
      return false;
    }
    // The tolerance holds in the world: in the mesh's units it shrinks with the largest scale.
    const double tolerance_m = options_.vegetation_hull_tolerance_m / static_cast<double>(shape.scale.maxCoeff());
    auto simplified = entry.simplified_hulls.find(tolerance_m);
    if (simplified == entry.simplified_hulls.end()) {
      simplified = entry.simplified_hulls.emplace(tolerance_m, simplify_convex_hull(**entry.hull, tolerance_m)).first;
    }
    object.mesh = simplified->second;
    scale_mesh(object.mesh, shape.scale);
    return true;
  }

  // A model names itself a building, or is static, tall and wide enough.
  void classify_buildings(std::size_t first_object, const Chain& chain) {
    std::vector<std::size_t> candidates;
    for (std::size_t i = first_object; i < world_.objects.size(); ++i) {
      if (unclassified_.count(i) != 0) candidates.push_back(i);
    }
    if (candidates.empty()) return;
    bool building = std::any_of(chain.names.begin(), chain.names.end(), name_suggests_building) ||
                    std::any_of(chain.uris.begin(), chain.uris.end(), name_suggests_building);
    if (!building && chain.is_static) {
      Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
      Eigen::Vector3d high = -low;
      for (const std::size_t i : candidates) {
        for (const auto& v : world_.objects[i].mesh.vertices_m) {
          const Eigen::Vector3d p = world_.objects[i].pose * v.cast<double>();
          low = low.cwiseMin(p);
          high = high.cwiseMax(p);
        }
      }
      const Eigen::Vector3d extent = high - low;
      building = extent.z() >= options_.building_min_height_m &&
                 extent.x() * extent.y() >= options_.building_min_footprint_m2;
    }
    if (building) {
      for (const std::size_t i : candidates) world_.objects[i].kind = ObjectKind::kBuilding;
    }
  }

  const SdfLoadOptions& options_;
  const Resolver& resolver_;
  WorldModel& world_;
  fs::path world_file_;
  std::map<std::string, std::shared_ptr<MeshEntry>> mesh_cache_;
  std::map<std::string, std::pair<std::string, int>>
      missing_meshes_;  // uri -> (first place, count)
  std::set<std::size_t> unclassified_;
  std::optional<std::string> unreadable_mesh_;
};

// sdformat's description of every element (sdf::init), built once per process on first use.
// Read-only afterwards: loads clone what they read from it.
const sdf::SDFPtr& sdf_description() {
  static const sdf::SDFPtr description = [] {
    auto built = std::make_shared<sdf::SDF>();
    sdf::init(built);
    return built;
  }();
  return description;
}

}  // namespace

namespace backend {

namespace {
Result<WorldModel> load_sdf_world_unguarded(const fs::path& path, const SdfLoadOptions& options);
}  // namespace

// sdformat throws on some malformed input instead of reporting an error (a version attribute that
// is no number went to std::stoi unchecked, found by the sdf fuzz target): the world is then
// malformed, not the program's end.
Result<WorldModel> load_sdf_world(const fs::path& path, const SdfLoadOptions& options) {
  try {
    return load_sdf_world_unguarded(path, options);
  } catch (const std::bad_alloc&) {
    throw;  // the program's own "out of memory" report
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kParse, path.string() + ": malformed SDF: sdformat stopped reading it (" + e.what() +
                                             "); check the file and its version attributes (such as version=\"1.9\")");
  }
}

namespace {
Result<WorldModel> load_sdf_world_unguarded(const fs::path& path, const SdfLoadOptions& options) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return make_error(ErrorCode::kIo, path.string() + ": SDF file not found");
  auto scan = scan_xml(path);
  if (!scan.ok()) return scan.error();
  if (options.round_segments < 3 || options.round_rings < 2 ||
      !(options.infinite_plane_size_m > 0.0)) {
    return make_error(
        ErrorCode::kInvalidArgument,
        path.string() + ": SDF options: at least 3 segments, 2 rings and a positive plane size");
  }

  const Resolver resolver(options);
  if (auto st = IncludeGraphCheck(resolver).check(path); !st) return st.error();
  WorldModel world;
  ConsoleCapture console;

  sdf::ParserConfig config;
  config.SetWarningsPolicy(sdf::EnforcementPolicy::WARN);
  config.SetFindCallback([&resolver](const std::string& uri) -> std::string {
    if (uri.rfind("model://", 0) != 0) return "";
    const auto found = resolver.resolve(uri, {});
    return found ? found->string() : std::string();
  });

  // sdformat builds every element of every included copy (about 20 ms per model): 252 trees of
  // two kinds cost seconds. World-level includes skytrace can resolve are therefore blanked out of
  // the text (keeping its lines) and instantiated from one sdformat load per model file, with the
  // include's name, pose and static. Includes with anything unusual (merge, placement_frame, a
  // pose in another frame, names referred to by frames or joints) stay with sdformat.
  std::string text = scan->text;
  std::vector<const IncludeSpec*> own_includes;
  if (scan->xml_error.empty() && scan->worlds == 1 && !scan->world_joints) {
    for (const auto& include : scan->includes) {
      if (include.unusual || include.uri.empty() || include.end <= include.begin) continue;
      if (include.uri.rfind("http://", 0) == 0 || include.uri.rfind("https://", 0) == 0) continue;
      if (include.pose && !parse_pose(*include.pose)) continue;
      if (include.name.empty() ? !scan->referenced_frames.empty()
                               : scan->referenced_frames.count(include.name) != 0) {
        continue;
      }
      for (std::size_t i = include.begin; i < include.end; ++i) {
        if (text[i] != '\n') text[i] = ' ';
      }
      own_includes.push_back(&include);
    }
  }

  // sdf::init builds the SDF description from sdformat's embedded spec files (tens of ms, 150 ms
  // under the sanitizers); every load of the process shares one (sdf_description()). Parsing
  // fills the root element in place, so each file gets a root of its own, but the descriptions of
  // the elements below it are shared: sdformat clones a description for every element it reads
  // and never changes the description itself. (A deep copy of the whole description per file was
  // a quarter of citysim's load time.)
  const auto fresh_sdf = []() {
    const sdf::ElementPtr& template_root = sdf_description()->Root();
    auto root = std::make_shared<sdf::Element>();
    root->SetName(template_root->GetName());
    root->SetRequired(template_root->GetRequired());
    root->SetCopyChildren(template_root->GetCopyChildren());
    root->SetDescription(template_root->GetDescription());
    for (std::size_t i = 0; i < template_root->GetAttributeCount(); ++i) {
      const sdf::ParamPtr attribute = template_root->GetAttribute(static_cast<unsigned>(i));
      root->AddAttribute(attribute->GetKey(), attribute->GetTypeName(), attribute->GetDefaultAsString(),
                         attribute->GetRequired(), attribute->GetDescription());
    }
    for (std::size_t i = 0; i < template_root->GetElementDescriptionCount(); ++i) {
      root->AddElementDescription(template_root->GetElementDescription(static_cast<unsigned>(i)));
    }
    auto copy = std::make_shared<sdf::SDF>();
    copy->Root(root);
    return copy;
  };

  // Parse to an element tree first: duplicate model names are made unique before the DOM load.
  sdf::Errors errors;
  sdf::SDFPtr parsed = fresh_sdf();
  const bool read = own_includes.empty() ? sdf::readFile(path.string(), config, parsed, errors)
                                         : sdf::readString(text, config, parsed, errors);
  if (!read) parsed.reset();
  std::map<std::string, std::pair<std::string, int>> missing_models;  // uri -> (first place, count)
  std::vector<std::string> fatal;
  const auto sort_errors = [&](const sdf::Errors& list) {
    for (const auto& error : list) {
      if (error.Code() == sdf::ErrorCode::URI_LOOKUP) {
        // "Unable to find uri[model://x]": the include is skipped, as Gazebo does.
        const std::string message = error.Message();
        const auto open = message.find('[');
        const auto close = message.rfind(']');
        const std::string uri =
            open != std::string::npos && close != std::string::npos && close > open
                ? message.substr(open + 1, close - open - 1)
                : message;
        auto& entry = missing_models[uri];
        if (entry.second++ == 0) {
          entry.first = error.FilePath() ? *error.FilePath() : path.string();
          if (error.LineNumber())
            entry.first.append(":").append(std::to_string(*error.LineNumber()));
        }
      } else {
        fatal.push_back(error_text(error));
      }
    }
  };
  sort_errors(errors);
  const auto fail = [&](const std::string& what) -> Result<WorldModel> {
    std::string message = scan->xml_error.empty() ? path.string() + ": " + what : scan->xml_error;
    for (const auto& line : fatal) message += "\n  " + line;
    for (const auto& line : console.lines()) message += "\n  sdformat: " + line;
    return make_error(ErrorCode::kParse, replace_string_source(message, path));
  };
  if (!parsed || !fatal.empty()) return fail("malformed SDF");

  sdf::ElementPtr world_element;
  for (auto element = parsed->Root()->GetElementImpl("world"); element;
       element = element->GetNextElement("world")) {
    if (options.world_name.empty() ||
        element->GetAttribute("name")->GetAsString() == options.world_name) {
      world_element = element;
      break;
    }
  }
  if (!options.world_name.empty() && !world_element) {
    return make_error(ErrorCode::kNotFound,
                      path.string() + ": no world named '" + options.world_name + "'");
  }
  std::map<std::string, ignition::math::Pose3d> saved_poses;
  if (world_element) {
    rename_duplicate_models(world_element, world.warnings);
    saved_poses = state_poses(world_element);
  }

  sdf::Root root;
  sort_errors(root.Load(parsed, config));
  if (!fatal.empty()) return fail("invalid SDF");

  SdfWalker walker(options, resolver, world, path);
  if (world_element) {
    const sdf::World* sdf_world = nullptr;
    for (uint64_t w = 0; w < root.WorldCount(); ++w) {
      if (root.WorldByIndex(w)->Element() == world_element ||
          root.WorldByIndex(w)->Name() == world_element->GetAttribute("name")->GetAsString()) {
        sdf_world = root.WorldByIndex(w);
        break;
      }
    }
    if (sdf_world == nullptr) return fail("the world could not be loaded");
    world.name = sdf_world->Name();

    if (const auto* sc = sdf_world->SphericalCoordinates()) {
      if (sc->Surface() != ignition::math::SphericalCoordinates::EARTH_WGS84) {
        world.warnings.push_back(where(world_element) +
                                 ": <spherical_coordinates> not on EARTH_WGS84, ignored");
      } else {
        GeoOrigin origin;
        origin.origin.latitude_deg = sc->LatitudeReference().Degree();
        origin.origin.longitude_deg = sc->LongitudeReference().Degree();
        origin.origin.height_m = sc->ElevationReference();
        origin.heading_deg = sc->HeadingOffset().Degree();
        world.geo_origin = origin;
        const auto element = world_element->GetElementImpl("spherical_coordinates");
        if (element && element->HasElement("world_frame_orientation")) {
          const auto orientation =
              element->GetElementImpl("world_frame_orientation")->Get<std::string>();
          if (orientation != "ENU") {
            world.warnings.push_back(where(element) + ": world_frame_orientation " + orientation +
                                     " read as ENU (the only orientation Gazebo implements)");
          }
        }
      }
    }

    for (uint64_t m = 0; m < sdf_world->ModelCount(); ++m) {
      const sdf::Model* model = sdf_world->ModelByIndex(m);
      ignition::math::Pose3d pose;
      const auto pose_errors = model->SemanticPose().Resolve(pose);
      if (!pose_errors.empty()) {
        world.warnings.push_back(
            where(model->Element()) + ": model " + model->Name() +
            " skipped, its pose cannot be resolved: " + error_text(pose_errors.front()));
        continue;
      }
      if (const auto saved = saved_poses.find(model->Name()); saved != saved_poses.end())
        pose = saved->second;
      walker.model(*model, to_isometry(pose), Chain{});
    }

    // The includes skytrace instantiates, each model file loaded once.
    std::set<std::string> names_in_use;
    for (uint64_t m = 0; m < sdf_world->ModelCount(); ++m)
      names_in_use.insert(sdf_world->ModelByIndex(m)->Name());
    std::map<std::string, std::unique_ptr<sdf::Root>> model_files;
    std::map<std::string, int> renamed;
    for (const IncludeSpec* include : own_includes) {
      const std::string place = path.string() + ":" + std::to_string(include->line);
      const auto found = resolver.resolve(include->uri, path.parent_path());
      std::string file;
      if (found)
        file =
            fs::is_directory(*found, ec) ? sdf::getModelFilePath(found->string()) : found->string();
      if (file.empty() || !fs::is_regular_file(file, ec)) {
        auto& entry = missing_models[include->uri];
        if (entry.second++ == 0) entry.first = place;
        continue;
      }
      auto& loaded = model_files[file];
      if (!loaded) {
        loaded = std::make_unique<sdf::Root>();
        sdf::Errors file_errors;
        sdf::SDFPtr file_sdf = fresh_sdf();
        if (!sdf::readFile(file, config, file_sdf, file_errors) && file_errors.empty()) {
          file_errors.emplace_back(sdf::ErrorCode::FILE_READ, "unable to read file [" + file + "]");
        }
        sort_errors(file_errors);
        if (fatal.empty()) sort_errors(loaded->Load(file_sdf, config));
        if (!fatal.empty())
          return fail("invalid model " + file + " included at line " +
                      std::to_string(include->line));
      }
      const sdf::Model* model = loaded->Model();
      if (model == nullptr) {
        world.warnings.push_back(place + ": " + include->uri + " holds no model, include skipped");
        continue;
      }
      std::string name = include->name.empty() ? model->Name() : include->name;
      if (!names_in_use.insert(name).second) {
        int suffix = 2;
        while (names_in_use.count(name + "_" + std::to_string(suffix)) != 0) ++suffix;
        ++renamed[name];
        name += "_" + std::to_string(suffix);
        names_in_use.insert(name);
      }
      // The include's pose replaces the model's own (SDFormat semantics); <state> wins over both.
      ignition::math::Pose3d pose = include->pose ? *parse_pose(*include->pose) : model->RawPose();
      if (const auto saved = saved_poses.find(name); saved != saved_poses.end())
        pose = saved->second;
      walker.model(*model, to_isometry(pose), Chain{},
                   SdfWalker::Overrides{name, include->uri, include->is_static});
    }
    for (const auto& [name, copies] : renamed) {
      world.warnings.push_back(
          path.string() + ": " + std::to_string(copies + 1) + " models named '" + name +
          "' (SDFormat needs unique names, Gazebo classic accepted them): copies renamed '" + name +
          "_2'...");
    }
    std::size_t roads = 0;
    for (auto road = world_element->GetElementImpl("road"); road;
         road = road->GetNextElement("road"))
      ++roads;
    if (roads > 0) {
      world.warnings.push_back(
          where(world_element) + ": " + std::to_string(roads) +
          " <road> element(s) skipped (flat ribbons on the ground do not block signals)");
    }
    if (sdf_world->ActorCount() > 0) {
      world.warnings.push_back(
          where(world_element) + ": " + std::to_string(sdf_world->ActorCount()) +
          " <actor> element(s) skipped (animated people are not obstacles here)");
    }
  } else if (const sdf::Model* model = root.Model()) {
    world.name = model->Name();
    ignition::math::Pose3d pose;
    (void)model->SemanticPose().Resolve(pose);
    walker.model(*model, to_isometry(pose), Chain{});
  } else {
    return make_error(ErrorCode::kNotFound,
                      path.string() + ": the SDF file holds no world and no model");
  }
  for (const auto& [uri, info] : missing_models) {
    world.warnings.push_back(info.first + ": model " + uri + " not found, " +
                             std::to_string(info.second) + " include" +
                             (info.second == 1 ? "" : "s") + " skipped");
  }
  if (!missing_models.empty()) {
    std::string dirs;
    for (const auto& dir : resolver.dirs()) dirs += (dirs.empty() ? "" : ", ") + dir.string();
    world.warnings.push_back("model:// URIs were searched in: " +
                             (dirs.empty() ? std::string("no model paths") : dirs));
  }
  walker.finish();
  if (walker.unreadable_mesh()) {
    return make_error(ErrorCode::kParse, replace_string_source(*walker.unreadable_mesh(), path));
  }
  if (!world.geo_origin && !options.geo_origin) {
    world.warnings.push_back(path.string() +
                             ": no <spherical_coordinates>: the world is not tied to the Earth");
  }
  if (options.geo_origin) world.geo_origin = options.geo_origin;
  for (const auto& line : console.lines()) world.warnings.push_back("sdformat: " + line);
  for (auto& warning : world.warnings) warning = replace_string_source(std::move(warning), path);
  return world;
}

}  // namespace
}  // namespace backend

}  // namespace skytrace::world
