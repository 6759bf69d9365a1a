// FFmpeg's functions the video files use (video_file.cpp), called through a table loaded the first
// time a video is opened: libavutil, libswscale, libavcodec and libavformat by their sonames
// (dlopen, RTLD_LOCAL), so that a program that never opens a video does not load FFmpeg and its
// ~120 codec libraries at its start. Internal.
#pragma once

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/display.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace kccd::overlay::detail {

/// One pointer per FFmpeg function used, named as the function.
struct FfmpegApi {
  decltype(&::av_log_set_level) av_log_set_level = nullptr;
  decltype(&::av_strerror) av_strerror = nullptr;
  decltype(&::av_malloc) av_malloc = nullptr;
  decltype(&::av_free) av_free = nullptr;
  decltype(&::av_sub_q) av_sub_q = nullptr;
  decltype(&::av_opt_set) av_opt_set = nullptr;
  decltype(&::av_display_rotation_get) av_display_rotation_get = nullptr;
  decltype(&::av_image_get_buffer_size) av_image_get_buffer_size = nullptr;
  decltype(&::av_image_fill_arrays) av_image_fill_arrays = nullptr;
  decltype(&::av_frame_alloc) av_frame_alloc = nullptr;
  decltype(&::av_frame_free) av_frame_free = nullptr;
  decltype(&::av_frame_unref) av_frame_unref = nullptr;
  decltype(&::av_frame_get_buffer) av_frame_get_buffer = nullptr;
  decltype(&::sws_getContext) sws_getContext = nullptr;
  decltype(&::sws_getCachedContext) sws_getCachedContext = nullptr;
  decltype(&::sws_scale) sws_scale = nullptr;
  decltype(&::sws_freeContext) sws_freeContext = nullptr;
  decltype(&::av_packet_alloc) av_packet_alloc = nullptr;
  decltype(&::av_packet_free) av_packet_free = nullptr;
  decltype(&::av_packet_unref) av_packet_unref = nullptr;
  decltype(&::av_packet_rescale_ts) av_packet_rescale_ts = nullptr;
  decltype(&::avcodec_find_encoder) avcodec_find_encoder = nullptr;
  decltype(&::avcodec_find_decoder) avcodec_find_decoder = nullptr;
  decltype(&::avcodec_get_name) avcodec_get_name = nullptr;
  decltype(&::avcodec_alloc_context3) avcodec_alloc_context3 = nullptr;
  decltype(&::avcodec_free_context) avcodec_free_context = nullptr;
  decltype(&::avcodec_open2) avcodec_open2 = nullptr;
  decltype(&::avcodec_parameters_to_context) avcodec_parameters_to_context = nullptr;
  decltype(&::avcodec_parameters_from_context) avcodec_parameters_from_context = nullptr;
  decltype(&::avcodec_send_packet) avcodec_send_packet = nullptr;
  decltype(&::avcodec_receive_frame) avcodec_receive_frame = nullptr;
  decltype(&::avcodec_send_frame) avcodec_send_frame = nullptr;
  decltype(&::avcodec_receive_packet) avcodec_receive_packet = nullptr;
  decltype(&::avformat_open_input) avformat_open_input = nullptr;
  decltype(&::avformat_find_stream_info) avformat_find_stream_info = nullptr;
  decltype(&::avformat_close_input) avformat_close_input = nullptr;
  decltype(&::av_read_frame) av_read_frame = nullptr;
  decltype(&::av_stream_get_side_data) av_stream_get_side_data = nullptr;
  decltype(&::avformat_alloc_output_context2) avformat_alloc_output_context2 = nullptr;
  decltype(&::avformat_query_codec) avformat_query_codec = nullptr;
  decltype(&::avformat_new_stream) avformat_new_stream = nullptr;
  decltype(&::avformat_write_header) avformat_write_header = nullptr;
  decltype(&::av_write_frame) av_write_frame = nullptr;
  decltype(&::av_write_trailer) av_write_trailer = nullptr;
  decltype(&::avformat_free_context) avformat_free_context = nullptr;
  decltype(&::avformat_get_riff_video_tags) avformat_get_riff_video_tags = nullptr;
  decltype(&::avformat_get_mov_video_tags) avformat_get_mov_video_tags = nullptr;
  decltype(&::av_codec_get_id) av_codec_get_id = nullptr;
  decltype(&::av_codec_get_tag) av_codec_get_tag = nullptr;
  decltype(&::avio_open) avio_open = nullptr;
  decltype(&::avio_closep) avio_closep = nullptr;
};

/// The table, the libraries loaded at the first call (thread-safe). Throws VideoFileError naming
/// the library or function that is missing; a failed load is tried again at the next call.
const FfmpegApi& ffmpeg();

/// The table when ffmpeg() has loaded it, else null (for destructors: never loads, never throws).
const FfmpegApi* loadedFfmpeg() noexcept;

}  // namespace kccd::overlay::detail
