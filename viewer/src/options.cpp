#include "options.h"

#include <cerrno>
#include <cstdlib>
#include <regex>

namespace strata::viewer {

namespace {

int parse_int(const std::string& flag, const std::string& text, int lo, int hi) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < lo || v > hi)
    throw UsageError(flag + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "], got '" + text + "'");
  return static_cast<int>(v);
}

double parse_double(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(v == v) || v > 1e300 || v < -1e300)
    throw UsageError(flag + " expects a finite number, got '" + text + "'");
  return v;
}

}  // namespace

std::string usage_text() {
  return R"(usage: strata-viewer [MODEL.strata | SCAN.obj|ply|off|stl] [options]

Without --screenshot: the interactive window (GLFW + Dear ImGui; press F1 for the shortcuts).

  --screenshot OUT.png     render without a window (EGL surfaceless) into OUT.png and exit;
                           prints one JSON line of timings and the GL error count
  --band K                 band the edits apply to (default 0: the cage of a model)
  --show K                 band drawn (default: the finest)
  --view V                 front|back|left|right|top|bottom|iso (default front)
  --size WxH               image or window size (default 1024x768)
  --shading flat|smooth    (default smooth)
  --wireframe              overlay the triangle edges
  --cage                   draw band 0's control net
  --vectors                draw the shown band rebuilt by displacement vectors (compare)
  --color error|intersections|scan|texture|none
                           prism volume error of the shown band, intersecting triangles, the
                           scan's own vertex colours (from its file), or its texture images (its
                           material library's map_Kd, or a PLY's TextureFile, read from beside
                           it); the default: texture, else colours, where the finest band has
                           them, else none
  --error-scale S          relative prism volume error drawn full red (default 0.05)
  --layers N               build an N-band layered model (2 .. 8) from a scan first
  --edit EDIT.json         apply an edit script to --band (repeatable; in order)
  --amplitude K=A ...      set band K's amplitude to A after the edits (0 mutes the band)
  --save OUT.strata        write the model (after edits and amplitudes)
  --export OUT.obj         write the mesh drawn (obj, ply, off or stl)
  --frames N               frames to render (timing); with --script-drag the frames of the drag
  --msaa N                 offscreen samples (default 4, 0 = none)
  --script-drag EDIT.json  window: drag each edit step over --frames frames, then release
  --benchmark              window: print per-frame times as JSON and exit after the script
  -h, --help               this text
)";
}

Options parse_options(int argc, char** argv) {
  Options o;
  std::vector<std::string> args(argv + 1, argv + argc);
  const std::regex amplitude_re(R"(^(\d+)=(.+)$)");
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError(a + " expects a value");
      return args[++i];
    };
    if (a == "-h" || a == "--help") {
      o.help = true;
    } else if (a == "--screenshot") {
      o.screenshot = value();
    } else if (a == "--band") {
      o.band = parse_int(a, value(), 0, 1000);
    } else if (a == "--show") {
      o.show = parse_int(a, value(), 0, 1000);
    } else if (a == "--view") {
      try {
        o.view = parse_view_preset(value());
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--view: ") + e.what());
      }
    } else if (a == "--size") {
      const std::string v = value();
      const auto x = v.find('x');
      if (x == std::string::npos) throw UsageError("--size expects WxH, got '" + v + "'");
      o.width = parse_int("--size width", v.substr(0, x), 16, 8192);
      o.height = parse_int("--size height", v.substr(x + 1), 16, 8192);
    } else if (a == "--shading") {
      const std::string v = value();
      if (v != "flat" && v != "smooth") throw UsageError("--shading expects flat or smooth, got '" + v + "'");
      o.smooth = v == "smooth";
    } else if (a == "--wireframe") {
      o.wireframe = true;
    } else if (a == "--cage") {
      o.cage = true;
    } else if (a == "--vectors") {
      o.vectors = true;
    } else if (a == "--color") {
      try {
        o.color = parse_color_mode(value());
        o.color_given = true;
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--color: ") + e.what());
      }
    } else if (a == "--error-scale") {
      o.error_scale = parse_double(a, value());
      if (o.error_scale <= 0) throw UsageError("--error-scale must be positive");
    } else if (a == "--layers") {
      o.build_bands = parse_int(a, value(), 2, 8);
    } else if (a == "--edit") {
      o.edits.push_back(value());
    } else if (a == "--amplitude") {
      std::smatch m;
      std::string v = value();
      do {
        if (!std::regex_match(v, m, amplitude_re))
          throw UsageError("--amplitude expects K=A, got '" + v + "'");
        o.amplitudes.push_back(
            {parse_int("--amplitude band", m[1], 0, 1000), parse_double("--amplitude", m[2])});
        if (i + 1 < args.size() && std::regex_match(args[i + 1], amplitude_re)) {
          v = args[++i];
        } else {
          break;
        }
      } while (true);
    } else if (a == "--save") {
      o.save = value();
    } else if (a == "--export") {
      o.export_mesh = value();
    } else if (a == "--frames") {
      o.frames = parse_int(a, value(), 1, 100000);
    } else if (a == "--msaa") {
      o.samples = parse_int(a, value(), 0, 16);
    } else if (a == "--script-drag") {
      o.script_drag = value();
    } else if (a == "--benchmark") {
      o.benchmark = true;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError("unknown option '" + a + "' (see --help)");
    } else if (o.input.empty()) {
      o.input = a;
    } else {
      throw UsageError("more than one input file ('" + o.input + "' and '" + a + "')");
    }
  }
  if (!o.screenshot.empty() && o.input.empty()) throw UsageError("--screenshot needs an input file");
  // The window saves and exports from its own panel (Ctrl+S, Ctrl+E); these were ignored there.
  if ((o.screenshot.empty() || !o.script_drag.empty()) && (!o.save.empty() || !o.export_mesh.empty()))
    throw UsageError(
        "--save and --export are for --screenshot renders without --script-drag (the window saves with "
        "Ctrl+S and exports with Ctrl+E)");
  return o;
}

}  // namespace strata::viewer
