#include "mapping/io/image_codec.h"

// clang-format off
#include <csetjmp>
#include <cstdio>  // jpeglib.h needs FILE and size_t first
#include <jpeglib.h>
#include <png.h>
// clang-format on

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "mapping/core/error.h"
#include "mapping/io/text_list.h"

namespace vdmap {
namespace {

// What a decoder hands back. Lives outside the functions that call setjmp, so nothing there
// has a destructor a longjmp could skip, and nothing it holds is a register-held local.
struct Decoded {
  cv::Mat image;
  int bits = 8;                      // per channel, of the file
  int channels = 0;                  // of the file
  cv::Size size;                     // of the file
  std::vector<unsigned char*> rows;  // PNG row pointers into image
  char error[JMSG_LENGTH_MAX + 200] = {};
};

void setError(Decoded* out, const char* message) { std::snprintf(out->error, sizeof out->error, "%s", message); }

// --- JPEG -------------------------------------------------------------------------------------

struct JpegErrors {
  jpeg_error_mgr mgr;  // first: libjpeg hands back a pointer to it
  std::jmp_buf jump;
  Decoded* out;
};

[[noreturn]] void jpegFail(j_common_ptr cinfo) {
  auto* errors = reinterpret_cast<JpegErrors*>(cinfo->err);
  char message[JMSG_LENGTH_MAX];
  (*cinfo->err->format_message)(cinfo, message);
  setError(errors->out, message);
  std::longjmp(errors->jump, 1);
}

// level -1 is a warning: libjpeg's word for damaged data it papers over (a premature end fills
// the rest with grey, corrupt entropy data is skipped). A map must not be made from that.
void jpegMessage(j_common_ptr cinfo, int level) {
  if (level < 0) jpegFail(cinfo);
}

void jpegSilent(j_common_ptr) {}

// Decodes RGB pixels (want_pixels, and the size is `expected`) or only reads the header. False
// with out->error on failure.
bool decodeJpeg(const std::string& bytes, bool want_pixels, cv::Size expected, Decoded* out) {
  jpeg_decompress_struct cinfo;
  JpegErrors errors;
  cinfo.err = jpeg_std_error(&errors.mgr);
  errors.mgr.error_exit = jpegFail;
  errors.mgr.emit_message = jpegMessage;
  errors.mgr.output_message = jpegSilent;
  errors.out = out;
  if (setjmp(errors.jump)) {
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  jpeg_read_header(&cinfo, TRUE);
  out->channels = cinfo.num_components;
  out->size = cv::Size(static_cast<int>(cinfo.image_width), static_cast<int>(cinfo.image_height));
  if (want_pixels && out->size == expected) {
    cinfo.out_color_space = JCS_RGB;
    jpeg_start_decompress(&cinfo);
    out->image.create(static_cast<int>(cinfo.output_height), static_cast<int>(cinfo.output_width), CV_8UC3);
    while (cinfo.output_scanline < cinfo.output_height) {
      JSAMPROW row = out->image.ptr(static_cast<int>(cinfo.output_scanline));
      jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);  // reads to the end-of-image marker: a cut file fails here too
  }
  jpeg_destroy_decompress(&cinfo);
  return true;
}

// --- PNG --------------------------------------------------------------------------------------

struct PngStream {
  const std::string* bytes;
  std::size_t pos = 0;
  std::jmp_buf jump;
  Decoded* out;
};

[[noreturn]] void pngFail(png_structp png, png_const_charp message) {
  auto* stream = static_cast<PngStream*>(png_get_error_ptr(png));
  setError(stream->out, message);
  std::longjmp(stream->jump, 1);
}

// libpng's warnings are about things it can read past without harm (an sRGB profile it
// dislikes, a damaged ancillary chunk it drops); damage to the image itself is an error. Silent.
void pngWarning(png_structp, png_const_charp) {}

void pngRead(png_structp png, png_bytep data, png_size_t n) {
  auto* stream = static_cast<PngStream*>(png_get_io_ptr(png));
  if (n > stream->bytes->size() - stream->pos) png_error(png, "the file ends early");
  std::memcpy(data, stream->bytes->data() + stream->pos, n);
  stream->pos += n;
}

// Decodes as 8-bit RGB (as_depth false) or as raw 16-bit grey (as_depth true). An image of
// another size than `expected` or (as_depth) another layout is not decoded: only the header's
// fields are filled and the image stays empty. False with out->error.
bool decodePng(const std::string& bytes, bool as_depth, cv::Size expected, Decoded* out) {
  PngStream stream{&bytes, 0, {}, out};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &stream, pngFail, pngWarning);
  if (!png) {
    setError(out, "out of memory");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (setjmp(stream.jump)) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  if (!info) png_error(png, "out of memory");
  png_set_read_fn(png, &stream, pngRead);
  png_read_info(png, info);
  const int color = png_get_color_type(png, info);
  out->bits = png_get_bit_depth(png, info) == 16 ? 16 : 8;
  out->channels = png_get_channels(png, info);
  if (color == PNG_COLOR_TYPE_PALETTE) out->channels = png_get_valid(png, info, PNG_INFO_tRNS) ? 4 : 3;
  out->size =
      cv::Size(static_cast<int>(png_get_image_width(png, info)), static_cast<int>(png_get_image_height(png, info)));
  const bool decode = out->size == expected && (!as_depth || (out->bits == 16 && color == PNG_COLOR_TYPE_GRAY));
  if (decode) {
    if (as_depth) {
      png_set_swap(png);  // PNG is big-endian, the Mat holds host (little-endian) words
    } else {
      png_set_palette_to_rgb(png);
      png_set_expand_gray_1_2_4_to_8(png);
      png_set_strip_16(png);
      png_set_strip_alpha(png);
      png_set_gray_to_rgb(png);
    }
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    const int rows_n = out->size.height;
    out->image.create(rows_n, out->size.width, as_depth ? CV_16UC1 : CV_8UC3);
    if (png_get_rowbytes(png, info) != out->image.step[0]) png_error(png, "unexpected row size after conversion");
    out->rows.resize(static_cast<std::size_t>(rows_n));
    for (int r = 0; r < rows_n; ++r) out->rows[static_cast<std::size_t>(r)] = out->image.ptr(r);
    png_read_image(png, out->rows.data());
    png_read_end(png, nullptr);  // up to IEND: a file cut after the pixels fails too
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

// --- both -------------------------------------------------------------------------------------

enum class ImageFormat { kPng, kJpeg, kOther };

ImageFormat formatOf(const std::string& bytes) {
  static const char kPngMagic[] = "\x89PNG\r\n\x1a\n";
  if (bytes.compare(0, 8, kPngMagic, 8) == 0) return ImageFormat::kPng;
  if (bytes.size() >= 3 && bytes.compare(0, 3, "\xFF\xD8\xFF", 3) == 0) return ImageFormat::kJpeg;
  return ImageFormat::kOther;
}

std::string readBytes(const std::filesystem::path& file, const std::string& what) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot decode " + what + ": cannot open the file");
  std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError(file.string(), "cannot decode " + what + ": cannot read the file");
  if (bytes.empty()) throw InputError(file.string(), "cannot decode " + what + ": the file is empty");
  bytes.shrink_to_fit();  // grown by doubling while read; a keyframe keeps these bytes
  return bytes;
}

std::string sizeText(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

cv::Mat decodeImage(const std::string& bytes, const std::filesystem::path& file, cv::Size expected, bool depth) {
  const std::string what = depth ? "depth image" : "colour image";
  const ImageFormat format = formatOf(bytes);
  if (format == ImageFormat::kOther)
    throw InputError(file.string(), "cannot decode " + what + ": not a " + (depth ? "PNG" : "PNG or JPEG") + " file");
  Decoded out;
  const bool ok =
      format == ImageFormat::kPng ? decodePng(bytes, depth, expected, &out) : decodeJpeg(bytes, !depth, expected, &out);
  if (!ok) throw InputError(file.string(), "cannot decode " + what + ": " + out.error + " (damaged or truncated)");
  if (depth && (out.bits != 16 || out.channels != 1 || format != ImageFormat::kPng))
    throw InputError(file.string(), "depth image must be 16-bit single-channel, got " + std::to_string(out.bits) +
                                        "-bit " + std::to_string(out.channels) + "-channel" +
                                        (format == ImageFormat::kJpeg ? " (JPEG)" : ""));
  if (out.size != expected)
    throw InputError(file.string(), what + " is " + sizeText(out.size) + " but the camera is " + sizeText(expected));
  return out.image;
}

// --- encoding -------------------------------------------------------------------------------
// Settings follow OpenCV 4.6's PngEncoder and JpegEncoder (modules/imgcodecs/src/grfmt_png.cpp,
// grfmt_jpeg.cpp), so a file is byte for byte what imencode wrote before vdmap encoded itself.

struct PngSink {
  std::string* bytes;
  std::jmp_buf jump;
  char error[200] = {};
};

[[noreturn]] void pngWriteFail(png_structp png, png_const_charp message) {
  auto* sink = static_cast<PngSink*>(png_get_error_ptr(png));
  std::snprintf(sink->error, sizeof sink->error, "%s", message);
  std::longjmp(sink->jump, 1);
}

void pngWrite(png_structp png, png_bytep data, png_size_t n) {
  static_cast<PngSink*>(png_get_io_ptr(png))->bytes->append(reinterpret_cast<const char*>(data), n);
}

void pngFlush(png_structp) {}

// Fills `bytes`; false with sink->error on failure. `rows` outlives the setjmp (see Decoded).
bool writePng(const cv::Mat& image, ChannelOrder order, PngCompression compression, std::vector<unsigned char*>* rows,
              PngSink* sink) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, sink, pngWriteFail, pngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (setjmp(sink->jump)) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  if (!info) png_error(png, "out of memory");
  png_set_write_fn(png, sink, pngWrite, pngFlush);
  if (compression == PngCompression::kFast) {
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_compression_level(png, 1);
    png_set_compression_strategy(png, 3);  // Z_RLE
  } else {
    png_set_compression_level(png, 1);
    png_set_compression_strategy(png, 0);  // Z_DEFAULT_STRATEGY
  }
  const int channels = image.channels();
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows),
               image.depth() == CV_16U ? 16 : 8, channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (order == ChannelOrder::kBgr) png_set_bgr(png);
  png_set_swap(png);  // 16-bit words: host (little-endian) to PNG's big-endian
  rows->resize(static_cast<std::size_t>(image.rows));
  for (int r = 0; r < image.rows; ++r) (*rows)[static_cast<std::size_t>(r)] = const_cast<unsigned char*>(image.ptr(r));
  png_write_image(png, rows->data());
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

struct JpegSink {
  jpeg_error_mgr mgr;  // first: libjpeg hands back a pointer to it
  std::jmp_buf jump;
  char error[JMSG_LENGTH_MAX] = {};
  unsigned char* buffer = nullptr;  // jpeg_mem_dest's, freed by the caller
  unsigned long size = 0;
  std::vector<unsigned char> row;
};

[[noreturn]] void jpegWriteFail(j_common_ptr cinfo) {
  auto* sink = reinterpret_cast<JpegSink*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, sink->error);
  std::longjmp(sink->jump, 1);
}

bool writeJpeg(const cv::Mat& image, int quality, ChannelOrder order, JpegSink* sink) {
  jpeg_compress_struct cinfo;
  cinfo.err = jpeg_std_error(&sink->mgr);
  sink->mgr.error_exit = jpegWriteFail;
  sink->mgr.output_message = jpegSilent;
  if (setjmp(sink->jump)) {
    jpeg_destroy_compress(&cinfo);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, &sink->buffer, &sink->size);
  cinfo.image_width = static_cast<JDIMENSION>(image.cols);
  cinfo.image_height = static_cast<JDIMENSION>(image.rows);
  cinfo.input_components = 3;
  cinfo.in_color_space = JCS_RGB;
  jpeg_set_defaults(&cinfo);
  cinfo.restart_interval = 0;
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  sink->row.resize(static_cast<std::size_t>(image.cols) * 3);
  for (int r = 0; r < image.rows; ++r) {
    JSAMPROW row = const_cast<unsigned char*>(image.ptr(r));
    if (order == ChannelOrder::kBgr) {
      for (int c = 0; c < image.cols; ++c)
        for (int k = 0; k < 3; ++k) sink->row[static_cast<std::size_t>(c * 3 + k)] = row[c * 3 + 2 - k];
      row = sink->row.data();
    }
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return true;
}

// The size the file's header gives, or 0x0 when it cannot be read (decodeImage then says why).
cv::Size headerSize(const std::string& bytes) {
  Decoded header;
  const ImageFormat format = formatOf(bytes);
  const bool ok = format == ImageFormat::kPng    ? decodePng(bytes, false, cv::Size(-1, -1), &header)
                  : format == ImageFormat::kJpeg ? decodeJpeg(bytes, false, cv::Size(), &header)
                                                 : false;
  return ok ? header.size : cv::Size();
}

}  // namespace

std::string encodePng(const cv::Mat& image, ChannelOrder order, PngCompression compression) {
  if (image.empty() || !(image.type() == CV_8UC1 || image.type() == CV_8UC3 || image.type() == CV_16UC1))
    throw std::invalid_argument("encodePng: an 8-bit grey or colour or a 16-bit grey image is expected");
  std::string bytes;
  std::vector<unsigned char*> rows;
  PngSink sink{&bytes, {}};
  if (!writePng(image, order, compression, &rows, &sink))
    throw std::runtime_error(std::string("cannot encode a PNG: ") + (sink.error[0] ? sink.error : "out of memory"));
  return bytes;
}

std::string encodeJpeg(const cv::Mat& image, int quality, ChannelOrder order) {
  if (image.empty() || image.type() != CV_8UC3 || quality < 1 || quality > 100)
    throw std::invalid_argument("encodeJpeg: an 8-bit colour image and a quality of 1..100 are expected");
  JpegSink sink;
  const bool ok = writeJpeg(image, quality, order, &sink);
  std::string bytes = ok ? std::string(reinterpret_cast<const char*>(sink.buffer), sink.size) : std::string();
  std::free(sink.buffer);
  if (!ok) throw std::runtime_error(std::string("cannot encode a JPEG: ") + sink.error);
  return bytes;
}

void writeImageFile(const std::filesystem::path& file, const cv::Mat& image, ChannelOrder order) {
  const std::string ext = asciiLower(file.extension().string());
  if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
    throw InputError(file.string(), "the image format follows the extension: .png, or .jpg / .jpeg for JPEG");
  const std::string bytes = ext == ".png" ? encodePng(image, order) : encodeJpeg(image, 95, order);
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw InputError(file.string(), "cannot write the image");
}

cv::Mat readColorImage(const std::filesystem::path& file, cv::Size expected, std::string* file_bytes) {
  std::string bytes = readBytes(file, "colour image");
  cv::Mat image = decodeImage(bytes, file, expected, false);
  if (file_bytes) *file_bytes = std::move(bytes);
  return image;
}

cv::Mat readDepthImage(const std::filesystem::path& file, cv::Size expected, std::string* file_bytes) {
  std::string bytes = readBytes(file, "depth image");
  cv::Mat image = decodeImage(bytes, file, expected, true);
  if (file_bytes) *file_bytes = std::move(bytes);
  return image;
}

cv::Mat decodeColorImage(const std::string& bytes, cv::Size expected, const std::string& name) {
  return decodeImage(bytes, name, expected, false);
}

cv::Mat decodeDepthImage(const std::string& bytes, cv::Size expected, const std::string& name) {
  return decodeImage(bytes, name, expected, true);
}

cv::Mat decodeColorImage(const std::string& bytes, const std::string& name) {
  return decodeImage(bytes, name, headerSize(bytes), false);
}

cv::Mat decodeDepthImage(const std::string& bytes, const std::string& name) {
  return decodeImage(bytes, name, headerSize(bytes), true);
}

}  // namespace vdmap
