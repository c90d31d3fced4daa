// JPEG half of image_codec.h on libjpeg (libjpeg-turbo's libjpeg 6.2 API).
// libjpeg reports errors through error_exit, which longjmps here: every setjmp
// below sits in a function whose frame holds only plain data, and the C++
// objects (buffers, the libjpeg structs' clean-up) live in the caller.
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>

// jpeglib.h needs FILE and size_t declared first
#include <jerror.h>
#include <jpeglib.h>

#include "render/image_codec.h"

namespace vlab::render {

namespace {

struct ErrorManager {
  jpeg_error_mgr base;  // first: libjpeg sees a jpeg_error_mgr*
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void OnErrorExit(j_common_ptr cinfo) {
  auto* error = reinterpret_cast<ErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, error->message);
  std::longjmp(error->jump, 1);
}

void OnMessage(j_common_ptr, int) {}  // warnings (corrupt data libjpeg recovers from) pass, as in OpenCV

void UseErrorManager(ErrorManager* error) {
  jpeg_std_error(&error->base);
  error->base.error_exit = OnErrorExit;
  error->base.emit_message = OnMessage;
  error->message[0] = '\0';
}

// ---- encoding

struct Encoder {
  jpeg_compress_struct cinfo;
  ErrorManager error;
  unsigned char* buffer;  // jpeg_mem_dest's (malloc)
  unsigned long size;
};

bool Compress(Encoder* e, const ImageView* image, std::size_t stride, int quality) {
  if (setjmp(e->error.jump)) return false;
  jpeg_create_compress(&e->cinfo);
  jpeg_mem_dest(&e->cinfo, &e->buffer, &e->size);
  e->cinfo.image_width = static_cast<JDIMENSION>(image->width);
  e->cinfo.image_height = static_cast<JDIMENSION>(image->height);
  e->cinfo.input_components = image->channels;
  e->cinfo.in_color_space = image->channels == 3 ? JCS_RGB : JCS_GRAYSCALE;
  // OpenCV's settings: libjpeg's defaults (YCbCr 4:2:0, baseline, no optimised tables)
  jpeg_set_defaults(&e->cinfo);
  e->cinfo.restart_interval = 0;
  jpeg_set_quality(&e->cinfo, quality, TRUE);
  jpeg_start_compress(&e->cinfo, TRUE);
  const auto* pixels = static_cast<const std::uint8_t*>(image->pixels);
  while (e->cinfo.next_scanline < e->cinfo.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(pixels + stride * e->cinfo.next_scanline);
    jpeg_write_scanlines(&e->cinfo, &row, 1);
  }
  jpeg_finish_compress(&e->cinfo);
  return true;
}

// ---- decoding

void InitSource(j_decompress_ptr) {}
void TermSource(j_decompress_ptr) {}

// all data is in memory from the start: needing more means the data was cut short
boolean FillInput(j_decompress_ptr cinfo) {
  ERREXIT(cinfo, JERR_INPUT_EOF);
  return FALSE;
}

void SkipInput(j_decompress_ptr cinfo, long count) {
  if (count <= 0) return;
  jpeg_source_mgr* src = cinfo->src;
  if (static_cast<unsigned long>(count) > src->bytes_in_buffer) ERREXIT(cinfo, JERR_INPUT_EOF);
  src->next_input_byte += count;
  src->bytes_in_buffer -= static_cast<std::size_t>(count);
}

struct Decoder {
  jpeg_decompress_struct cinfo;
  ErrorManager error;
  jpeg_source_mgr source;
  bool created;
};

bool ReadHeader(Decoder* d, const std::uint8_t* bytes, std::size_t size) {
  if (setjmp(d->error.jump)) return false;
  jpeg_create_decompress(&d->cinfo);
  d->created = true;
  d->source.init_source = InitSource;
  d->source.fill_input_buffer = FillInput;
  d->source.skip_input_data = SkipInput;
  d->source.resync_to_restart = jpeg_resync_to_restart;
  d->source.term_source = TermSource;
  d->source.next_input_byte = bytes;
  d->source.bytes_in_buffer = size;
  d->cinfo.src = &d->source;
  jpeg_read_header(&d->cinfo, TRUE);
  return true;
}

bool ReadRows(Decoder* d, int channels, std::uint8_t* out) {
  if (setjmp(d->error.jump)) return false;
  d->cinfo.out_color_space = channels == 3 ? JCS_RGB : JCS_GRAYSCALE;
  jpeg_start_decompress(&d->cinfo);
  const std::size_t stride = static_cast<std::size_t>(d->cinfo.output_width) * channels;
  while (d->cinfo.output_scanline < d->cinfo.output_height) {
    JSAMPROW row = out + stride * d->cinfo.output_scanline;
    jpeg_read_scanlines(&d->cinfo, &row, 1);
  }
  jpeg_finish_decompress(&d->cinfo);
  return true;
}

}  // namespace

void EncodeJpeg(const ImageView& image, int quality, std::vector<std::uint8_t>* jpeg) {
  const std::size_t stride = codec_detail::CheckedStride(image, "JPEG encoding");
  if (image.depth != 8 || (image.channels != 1 && image.channels != 3)) {
    throw ImageCodecError("JPEG encoding: needs 8-bit grey or RGB, not " + std::to_string(image.channels) +
                          " channels of " + std::to_string(image.depth) + " bits");
  }
  quality = quality < 1 ? 1 : quality > 100 ? 100 : quality;
  auto* e = static_cast<Encoder*>(std::calloc(1, sizeof(Encoder)));
  if (!e) throw ImageCodecError("JPEG encoding: out of memory");
  e->cinfo.err = &e->error.base;
  UseErrorManager(&e->error);
  const bool ok = Compress(e, &image, stride, quality);
  jpeg_destroy_compress(&e->cinfo);
  std::string message = e->error.message;
  bool copied = false;
  if (ok) {
    try {
      jpeg->assign(e->buffer, e->buffer + e->size);
      copied = true;
    } catch (...) {
      message = "out of memory";
    }
  }
  std::free(e->buffer);
  std::free(e);
  if (!copied) throw ImageCodecError("JPEG encoding failed: " + message);
}

namespace codec_detail {

void DecodeJpeg(const std::uint8_t* bytes, std::size_t size, DecodeMode mode, Image* out) {
  // the libjpeg state in plain memory, freed on every path below
  auto* d = static_cast<Decoder*>(std::calloc(1, sizeof(Decoder)));
  if (!d) throw ImageCodecError("JPEG: out of memory");
  struct Free {
    Decoder* d;
    ~Free() {
      if (d->created) jpeg_destroy_decompress(&d->cinfo);
      std::free(d);
    }
  } free_decoder{d};
  d->cinfo.err = &d->error.base;
  UseErrorManager(&d->error);
  if (!ReadHeader(d, bytes, size)) throw ImageCodecError(std::string("JPEG: bad header: ") + d->error.message);
  if (d->cinfo.num_components == 4) throw ImageCodecError("JPEG: CMYK/YCCK images are not supported");
  const int channels = mode == DecodeMode::kGray                                   ? 1
                       : mode == DecodeMode::kColor || d->cinfo.num_components > 1 ? 3
                                                                                   : 1;
  Allocate(static_cast<int>(d->cinfo.image_width), static_cast<int>(d->cinfo.image_height), channels, 8, "JPEG", out);
  if (!ReadRows(d, channels, out->bytes.data())) {
    throw ImageCodecError(std::string("JPEG: bad image data: ") + d->error.message);
  }
}

}  // namespace codec_detail

}  // namespace vlab::render
