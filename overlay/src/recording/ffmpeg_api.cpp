// FFmpeg loaded by its sonames at the first video opened (see ffmpeg_api.hpp).
#include "ffmpeg_api.hpp"

#include <dlfcn.h>

#include <atomic>
#include <mutex>
#include <string>
#include <type_traits>

#include "kccd/overlay/recording/video_file.hpp"

namespace kccd::overlay::detail {

namespace {

// FFmpeg's library `name` of the major version whose headers this file was compiled with
// (libavcodec.so.59 for FFmpeg 5.1; Debian's package libavcodec59): a library of another major
// version has other structures.
void* openFfmpegLibrary(const char* name, int major) {
  const std::string file = "lib" + std::string(name) + ".so." + std::to_string(major);
  void* handle = ::dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = ::dlerror();
    throw VideoFileError("FFmpeg's " + file + " cannot be loaded (" + (why == nullptr ? "no reason given" : why) +
                         "; on Debian: apt install lib" + name + std::to_string(major) + ")");
  }
  return handle;
}

std::mutex ffmpeg_mutex;  // held while the libraries load
FfmpegApi ffmpeg_table;
// Set (release) once the table is whole; read (acquire) without the lock by every call after, so
// the per-frame calls take no lock.
std::atomic<bool> ffmpeg_loaded{false};

}  // namespace

const FfmpegApi* loadedFfmpeg() noexcept {
  return ffmpeg_loaded.load(std::memory_order_acquire) ? &ffmpeg_table : nullptr;
}

const FfmpegApi& ffmpeg() {
  if (ffmpeg_loaded.load(std::memory_order_acquire)) return ffmpeg_table;
  const std::lock_guard lock(ffmpeg_mutex);
  if (ffmpeg_loaded.load(std::memory_order_relaxed)) return ffmpeg_table;  // loaded while this call waited
  // Each library after those it needs; a handle opened twice (a failed load tried again) is counted
  // by the loader and stays, as the libraries stay loaded for the process's life anyway.
  void* util = openFfmpegLibrary("avutil", LIBAVUTIL_VERSION_MAJOR);
  void* scale = openFfmpegLibrary("swscale", LIBSWSCALE_VERSION_MAJOR);
  void* codec = openFfmpegLibrary("avcodec", LIBAVCODEC_VERSION_MAJOR);
  void* format = openFfmpegLibrary("avformat", LIBAVFORMAT_VERSION_MAJOR);
  FfmpegApi found;
  std::string missing;
  auto symbol = [&](void* handle, auto& entry, const char* name) {
    entry = reinterpret_cast<std::remove_reference_t<decltype(entry)>>(::dlsym(handle, name));
    if (entry == nullptr && missing.empty()) missing = name;
  };
#define KCCD_FFMPEG_SYMBOL(handle, name) symbol(handle, found.name, #name)
  KCCD_FFMPEG_SYMBOL(util, av_log_set_level);
  KCCD_FFMPEG_SYMBOL(util, av_strerror);
  KCCD_FFMPEG_SYMBOL(util, av_malloc);
  KCCD_FFMPEG_SYMBOL(util, av_free);
  KCCD_FFMPEG_SYMBOL(util, av_sub_q);
  KCCD_FFMPEG_SYMBOL(util, av_opt_set);
  KCCD_FFMPEG_SYMBOL(util, av_display_rotation_get);
  KCCD_FFMPEG_SYMBOL(util, av_image_get_buffer_size);
  KCCD_FFMPEG_SYMBOL(util, av_image_fill_arrays);
  KCCD_FFMPEG_SYMBOL(util, av_frame_alloc);
  KCCD_FFMPEG_SYMBOL(util, av_frame_free);
  KCCD_FFMPEG_SYMBOL(util, av_frame_unref);
  KCCD_FFMPEG_SYMBOL(util, av_frame_get_buffer);
  KCCD_FFMPEG_SYMBOL(scale, sws_getContext);
  KCCD_FFMPEG_SYMBOL(scale, sws_getCachedContext);
  KCCD_FFMPEG_SYMBOL(scale, sws_scale);
  KCCD_FFMPEG_SYMBOL(scale, sws_freeContext);
  KCCD_FFMPEG_SYMBOL(codec, av_packet_alloc);
  KCCD_FFMPEG_SYMBOL(codec, av_packet_free);
  KCCD_FFMPEG_SYMBOL(codec, av_packet_unref);
  KCCD_FFMPEG_SYMBOL(codec, av_packet_rescale_ts);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_find_encoder);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_find_decoder);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_get_name);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_alloc_context3);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_free_context);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_open2);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_parameters_to_context);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_parameters_from_context);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_send_packet);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_receive_frame);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_send_frame);
  KCCD_FFMPEG_SYMBOL(codec, avcodec_receive_packet);
  KCCD_FFMPEG_SYMBOL(format, avformat_open_input);
  KCCD_FFMPEG_SYMBOL(format, avformat_find_stream_info);
  KCCD_FFMPEG_SYMBOL(format, avformat_close_input);
  KCCD_FFMPEG_SYMBOL(format, av_read_frame);
  KCCD_FFMPEG_SYMBOL(format, av_stream_get_side_data);
  KCCD_FFMPEG_SYMBOL(format, avformat_alloc_output_context2);
  KCCD_FFMPEG_SYMBOL(format, avformat_query_codec);
  KCCD_FFMPEG_SYMBOL(format, avformat_new_stream);
  KCCD_FFMPEG_SYMBOL(format, avformat_write_header);
  KCCD_FFMPEG_SYMBOL(format, av_write_frame);
  KCCD_FFMPEG_SYMBOL(format, av_write_trailer);
  KCCD_FFMPEG_SYMBOL(format, avformat_free_context);
  KCCD_FFMPEG_SYMBOL(format, avformat_get_riff_video_tags);
  KCCD_FFMPEG_SYMBOL(format, avformat_get_mov_video_tags);
  KCCD_FFMPEG_SYMBOL(format, av_codec_get_id);
  KCCD_FFMPEG_SYMBOL(format, av_codec_get_tag);
  KCCD_FFMPEG_SYMBOL(format, avio_open);
  KCCD_FFMPEG_SYMBOL(format, avio_closep);
#undef KCCD_FFMPEG_SYMBOL
  if (!missing.empty()) throw VideoFileError("FFmpeg's libraries have no " + missing + " (another version of FFmpeg?)");
  ffmpeg_table = found;
  ffmpeg_loaded.store(true, std::memory_order_release);
  return ffmpeg_table;
}

}  // namespace kccd::overlay::detail
