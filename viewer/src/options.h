//! \file options.h
//! The command line of strata-viewer. No OpenGL here.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "camera.h"
#include "colormap.h"

namespace strata::viewer {

//! A command-line error: main prints "strata-viewer: error: <message>" and exits 1.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string input;       //!< MODEL.strata or SCAN.(obj|ply|off|stl); may be empty (window)
  std::string screenshot;  //!< --screenshot OUT.png: headless render, then exit
  int band = 0;            //!< --band K: the band edits apply to (and the window edits)
  int show = -1;           //!< --show K: the band drawn (-1: the finest)
  ViewPreset view = ViewPreset::Front;
  int width = 1024, height = 768;     //!< --size WxH
  bool smooth = true;                 //!< --shading smooth|flat
  bool wireframe = false;             //!< --wireframe
  bool cage = false;                  //!< --cage: draw band 0's control net
  bool vectors = false;               //!< --vectors: band shown rebuilt by displacement vectors
  ColorMode color = ColorMode::None;  //!< --color error|intersections|scan|none
  //! --color was given; without it a document whose finest band has vertex colours (a coloured
  //! scan) shows them (initial_color_mode()).
  bool color_given = false;
  double error_scale = 0.05;       //!< --error-scale S: relative prism error drawn full red
  int build_bands = 0;             //!< --layers N: build an N-band model from a scan first (0: no)
  std::vector<std::string> edits;  //!< --edit EDIT.json (repeatable), applied in order
  std::vector<std::pair<int, double>> amplitudes;  //!< --amplitude K=A ..., after the edits
  std::string save;         //!< --save OUT.strata: the model after edits and amplitudes
  std::string export_mesh;  //!< --export OUT.(obj|ply|off|stl): the mesh drawn
  int frames = 1;           //!< --frames N: frames rendered (timing; window: scripted run)
  int samples = 4;          //!< --msaa N: samples of the offscreen target (0: none)
  std::string script_drag;  //!< --script-drag EDIT.json: window, drag each step over the frames
  bool benchmark = false;   //!< --benchmark: window, print per-frame JSON and exit
  bool help = false;
};

//! Parses argv. \throw UsageError naming the bad argument.
Options parse_options(int argc, char** argv);
//! The --help text.
std::string usage_text();

}  // namespace strata::viewer
