#pragma once
// The optional Open3D peer plugin of `vdmap bench` (libvdmap_open3d_peer.so beside the vdmap
// binary; app/bench/open3d/CMakeLists.txt), loaded on first use and kept for the life of the process.
#include <string>

namespace vdmap::app {

/// The plugin's dlopen handle, or nullptr with *why saying what is missing (the same answer on
/// every call; *why is only written on failure).
void* open3dPeerPlugin(std::string* why);

/// Looks up `name` in the plugin (nullptr with *why set when the plugin or the symbol is missing).
void* open3dPeerSymbol(const char* name, std::string* why);

}  // namespace vdmap::app
