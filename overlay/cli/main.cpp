// kccd-all: every kccd subcommand (the `kccd` launcher runs this program for all but its light ones).
#include <array>
#include <iostream>

#include "cli_app.hpp"
#include "cli_output.hpp"
#include "kccd/render/gl_context.hpp"

int main(int argc, char** argv) {
  using namespace kccd::cli;
  static constexpr std::array<Adder, 13> kCommands = {addInfo,   addQuery, addFit,    addPairs,   addImport,
                                                      addRender, addCalib, addSynth,  addOverlay, addCheck,
                                                      addGolden, addBag,   addDataset};
  AppHooks hooks;
  // A silent change of GL back end changes the renderer string (and may change pixels): said once.
  hooks.after_run = [] {
    const std::string reason = kccd::render::GlContext::lastFallback();
    if (!reason.empty())
      std::cerr << "kccd: warning: no EGL context (" << oneLine(reason)
                << "): rendered with OSMesa (KCCD_GL=egl makes this an error, KCCD_GL=osmesa chooses OSMesa)\n";
  };
  // No GL context (KCCD_GL, EGL, OSMesa): not an input error, and not a bug of kccd's.
  hooks.environment_error = [](const std::exception& e) {
    return dynamic_cast<const kccd::render::GlContextError*>(&e) != nullptr;
  };
  return runApp(argc, argv, kCommands, hooks);
}
