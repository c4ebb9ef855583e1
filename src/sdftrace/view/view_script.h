// Scripted input for the viewer (`sdftrace view --script FILE`, docs/viewer.md): one command per
// line, the same moves and switches the mouse, the keys and the panel make, so that a test (or a
// demo) drives the window without a person. '#' starts a comment.
//
//   orbit DX DY       a left-button drag of (DX, DY) pixels
//   pan DX DY         a right-button drag
//   zoom CLICKS       mouse-wheel clicks (> 0: closer)
//   fly F R U         move along the view, right and up axes (world units)
//   reset             the scene's own camera
//   set KEY VALUE     a render option by its scene key (render --list-options), e.g. set omega 1.5
//   tracer classic|enhanced
//   aov NAME          the AOV shown: color, depth, normal, steps, error, trav_steps, isect_tests,
//                     shadow, ao
//   frames N          full-resolution frames accumulated when the view stops
//   wait              until the picture is refined (every frame accumulated)
//   screenshot PATH   the AOV shown, as `render --aov` writes it (.png, .exr, .pfm)
//   grab PATH         the whole window as drawn, panel included (.png)
//   command           print the `sdftrace render` command that reproduces the view on stdout
//   reload            read the scene file again
//   quit
#pragma once
#include <string>
#include <vector>

namespace sdft {

struct ViewCommand {
    std::string name;
    std::vector<std::string> args;
    std::vector<double> numbers;  // the numeric arguments (orbit, pan, zoom, fly, frames)
    int line = 0;
};

// Checks every line (the command, its number of arguments, numbers); throws InputError
// "<source>:<line>: ..." naming what is accepted.
std::vector<ViewCommand> parseViewScript(const std::string& text, const std::string& source);

}  // namespace sdft
