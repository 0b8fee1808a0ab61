// The OSMesa off-screen context. libOSMesa is opened with dlopen rather than linked: a missing
// library then becomes a clear error instead of a loader failure, and its gl* exports never
// compete with libGL's (the function table comes from OSMesaGetProcAddress).
#include <dlfcn.h>

#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "render/context.h"

namespace vdmap::render {
namespace {

// From GL/osmesa.h (not included: it pulls in GL/gl.h with linked prototypes).
using OSMesaContext = void*;
constexpr int kOsmesaFormat = 0x22, kOsmesaRgba = 0x1908, kOsmesaDepthBits = 0x30, kOsmesaStencilBits = 0x31,
              kOsmesaAccumBits = 0x32, kOsmesaProfile = 0x33, kOsmesaCoreProfile = 0x34, kOsmesaMajor = 0x36,
              kOsmesaMinor = 0x37;
using CreateAttribsFn = OSMesaContext (*)(const int*, OSMesaContext);
using MakeCurrentFn = unsigned char (*)(OSMesaContext, void*, GLenum, GLsizei, GLsizei);
using DestroyFn = void (*)(OSMesaContext);
using GetProcAddressFn = GlProc (*)(const char*);

class OsmesaContext final : public Context {
 public:
  OsmesaContext() {
    const char* env = std::getenv("VDMAP_OSMESA_LIBRARY");
    const std::vector<std::string> names =
        env && *env ? std::vector<std::string>{env}
                    : std::vector<std::string>{"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"};
    for (const std::string& name : names)
      if ((lib_ = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL))) break;
    if (!lib_)
      throw std::runtime_error("off-screen rendering needs OSMesa, which is not available (" + names.front() + ": " +
                               dlerror() + "); install libosmesa6 (Debian) or set VDMAP_OSMESA_LIBRARY");
    create_ = reinterpret_cast<CreateAttribsFn>(dlsym(lib_, "OSMesaCreateContextAttribs"));
    make_current_ = reinterpret_cast<MakeCurrentFn>(dlsym(lib_, "OSMesaMakeCurrent"));
    destroy_ = reinterpret_cast<DestroyFn>(dlsym(lib_, "OSMesaDestroyContext"));
    get_proc_ = reinterpret_cast<GetProcAddressFn>(dlsym(lib_, "OSMesaGetProcAddress"));
    if (!create_ || !make_current_ || !destroy_ || !get_proc_) {
      dlclose(lib_);
      throw std::runtime_error("the OSMesa library found lacks OSMesaCreateContextAttribs (need Mesa >= 12)");
    }
    const int attribs[] = {kOsmesaFormat,
                           kOsmesaRgba,
                           kOsmesaDepthBits,
                           24,
                           kOsmesaStencilBits,
                           0,
                           kOsmesaAccumBits,
                           0,
                           kOsmesaProfile,
                           kOsmesaCoreProfile,
                           kOsmesaMajor,
                           3,
                           kOsmesaMinor,
                           3,
                           0};
    ctx_ = create_(attribs, nullptr);
    if (!ctx_) {
      dlclose(lib_);
      throw std::runtime_error("OSMesa could not create an OpenGL 3.3 core context");
    }
    makeCurrent();
    const GetProcAddressFn get = get_proc_;
    gl_ = loadGl([get](const char* name) { return get(name); });
  }
  ~OsmesaContext() override {
    destroy_(ctx_);
    // The library stays loaded: Mesa keeps per-process state that does not survive dlclose.
  }
  void makeCurrent() override {
    // Everything is drawn into framebuffer objects; the window-system buffer is a 1x1 dummy.
    if (!make_current_(ctx_, &dummy_, GL_UNSIGNED_BYTE, 1, 1)) throw std::runtime_error("OSMesaMakeCurrent failed");
  }
  const Gl& gl() const override { return gl_; }

 private:
  void* lib_ = nullptr;
  OSMesaContext ctx_ = nullptr;
  CreateAttribsFn create_ = nullptr;
  MakeCurrentFn make_current_ = nullptr;
  DestroyFn destroy_ = nullptr;
  GetProcAddressFn get_proc_ = nullptr;
  unsigned char dummy_[4] = {};
  Gl gl_;
};

}  // namespace

std::string Context::description() const {
  auto str = [this](GLenum name) {
    const GLubyte* s = gl().GetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_VENDOR) + " / " + str(GL_RENDERER) + " / " + str(GL_VERSION);
}

std::unique_ptr<Context> createOffscreenContext() { return std::make_unique<OsmesaContext>(); }

}  // namespace vdmap::render
