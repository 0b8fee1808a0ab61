#include "app/bench/peer_plugin.h"

#include <dlfcn.h>

#include <filesystem>

namespace vdmap::app {

void* open3dPeerPlugin(std::string* why) {
  static void* handle = nullptr;
  static std::string error;
  static bool tried = false;
  if (!tried) {
    tried = true;
    const std::filesystem::path plugin =
        std::filesystem::read_symlink("/proc/self/exe").parent_path() / "libvdmap_open3d_peer.so";
    // RTLD_LOCAL: Open3D's symbols (and the GL libraries it pulls in) do not join the global
    // namespace the renderer resolves through. The library stays loaded for the life of the
    // process: Open3D registers atexit handlers and static destructors that must not outlive
    // their code.
    handle = dlopen(plugin.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle)
      error = std::filesystem::exists(plugin) ? std::string(dlerror())
                                              : plugin.string() + " not built (configure with libopen3d-dev installed)";
  }
  if (!handle) *why = error;
  return handle;
}

void* open3dPeerSymbol(const char* name, std::string* why) {
  void* handle = open3dPeerPlugin(why);
  if (!handle) return nullptr;
  void* symbol = dlsym(handle, name);
  if (!symbol) *why = std::string("the Open3D peer plugin has no ") + name + " (rebuild it)";
  return symbol;
}

}  // namespace vdmap::app
