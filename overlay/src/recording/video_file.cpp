#include "kccd/overlay/recording/video_file.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#include <unistd.h>

#include "ffmpeg_api.hpp"

#include <opencv2/core.hpp>

namespace kccd::overlay {

namespace {

// FFmpeg's functions; the first call loads the libraries (throws VideoFileError when it cannot).
const detail::FfmpegApi& ff() { return detail::ffmpeg(); }

std::string ffmpegError(int code) {
  std::array<char, AV_ERROR_MAX_STRING_SIZE> text{};
  ff().av_strerror(code, text.data(), text.size());
  return text.data();
}

// The level KCCD_FFMPEG_LOGLEVEL asks for (an FFmpeg level: -8 quiet ... 56 trace), else `otherwise`.
int requestedLogLevel(int otherwise) {
  const char* v = std::getenv("KCCD_FFMPEG_LOGLEVEL");
  if (v == nullptr || *v == '\0') return otherwise;
  char* end = nullptr;
  const long level = std::strtol(v, &end, 10);
  return end != v && *end == '\0' && level >= AV_LOG_QUIET && level <= AV_LOG_TRACE ? static_cast<int>(level)
                                                                                    : otherwise;
}

// FFmpeg's own log lines stay unprinted (the suite reports each failure once, in its own words)
// unless KCCD_FFMPEG_LOGLEVEL asks for them; set once, before the first file is opened.
void quietByDefault() {
  static std::once_flag once;
  std::call_once(once, [] { ff().av_log_set_level(requestedLogLevel(AV_LOG_QUIET)); });
}

// The FourCC tables of the containers this suite writes and reads most (AVI's, then MP4's), as
// FFmpeg's lookups take them: null-terminated.
const AVCodecTag* const* usualTags() {
  static const AVCodecTag* const tables[] = {ff().avformat_get_riff_video_tags(), ff().avformat_get_mov_video_tags(),
                                             nullptr};
  return tables;
}

std::string fourccText(std::uint32_t tag) {
  std::string out;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((tag >> (8 * i)) & 0xFF);
    if (c > ' ' && c < 127) out += c;
  }
  return out;
}

// The codec a FourCC names, case ignored for the usual spellings.
AVCodecID codecOf(const std::string& four) {
  std::string lower;
  for (const char c : four) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == "mp4v" || lower == "xvid" || lower == "divx" || lower == "fmp4" || lower == "dx50")
    return AV_CODEC_ID_MPEG4;
  if (lower == "mjpg") return AV_CODEC_ID_MJPEG;
  if (lower == "ffv1") return AV_CODEC_ID_FFV1;
  if (lower == "ffvh") return AV_CODEC_ID_FFVHUFF;
  if (lower == "avc1" || lower == "h264" || lower == "x264") return AV_CODEC_ID_H264;
  if (lower == "hvc1" || lower == "hevc" || lower == "hev1" || lower == "h265") return AV_CODEC_ID_HEVC;
  if (lower == "vp80") return AV_CODEC_ID_VP8;
  if (lower == "vp90") return AV_CODEC_ID_VP9;
  if (lower == "av01") return AV_CODEC_ID_AV1;
  return ff().av_codec_get_id(usualTags(), fourccCode(four));
}

}  // namespace

std::uint32_t fourccCode(const std::string& four) {
  if (four.size() != 4) return 0;
  std::uint32_t code = 0;
  for (int i = 3; i >= 0; --i) code = (code << 8) | static_cast<unsigned char>(four[static_cast<std::size_t>(i)]);
  return code;
}

VideoLibraryPreparation::VideoLibraryPreparation() {
  try {
    thread_ = std::thread([] {
      try {
        quietByDefault();  // loads the libraries
      } catch (...) {
        // Reported by the first reader or writer, which tries again.
      }
    });
  } catch (const std::system_error&) {
    // No thread: the first reader or writer loads them.
  }
}

VideoLibraryPreparation::~VideoLibraryPreparation() {
  if (thread_.joinable()) thread_.join();
}

// ---------------------------------------------------------------------------------------------
// Reading

struct VideoFileReader::Impl {
  AVFormatContext* format = nullptr;
  AVCodecContext* decoder = nullptr;
  AVPacket* packet = nullptr;
  AVFrame* frame = nullptr;
  SwsContext* scale = nullptr;
  AVFrame* converted = nullptr;  // BGR at the coded size, rows aligned to 32 bytes
  int stream = -1;
  int rotation = 0;       // clockwise degrees the decoded picture is turned by: 0, 90, 180, 270
  bool draining = false;  // the end of the file was sent to the decoder

  ~Impl() {
    const detail::FfmpegApi* f = detail::loadedFfmpeg();
    if (f == nullptr) return;  // nothing of FFmpeg's was made
    f->sws_freeContext(scale);
    f->av_frame_free(&converted);
    f->av_frame_free(&frame);
    f->av_packet_free(&packet);
    f->avcodec_free_context(&decoder);
    f->avformat_close_input(&format);
  }

  // The decoded frame in BGR, turned upright. As OpenCV's FFmpeg capture converts (so the pixels
  // are the same to the bit): the whole coded picture (e.g. 1920x1088 for 1080p H.264) into a
  // buffer of rows aligned to 32 bytes, bicubic, swscale's default colour matrix; then the
  // picture's own size from its top-left corner.
  void convert(cv::Mat& bgr) {
    const int w = frame->width, h = frame->height;
    if (w <= 0 || h <= 0 || frame->format < 0) throw VideoFileError("a frame without a picture");
    const int cw = std::max(w, decoder->coded_width), ch = std::max(h, decoder->coded_height);
    if (converted == nullptr || converted->width != cw || converted->height != ch) {
      ff().av_frame_free(&converted);
      converted = ff().av_frame_alloc();
      if (converted == nullptr) throw std::bad_alloc();
      converted->format = AV_PIX_FMT_BGR24;
      converted->width = cw;
      converted->height = ch;
      if (ff().av_frame_get_buffer(converted, 32) < 0) throw std::bad_alloc();
    }
    scale = ff().sws_getCachedContext(scale, cw, ch, static_cast<AVPixelFormat>(frame->format), cw, ch,
                                      AV_PIX_FMT_BGR24, SWS_BICUBIC, nullptr, nullptr, nullptr);
    if (scale == nullptr) throw VideoFileError("a pixel format swscale cannot convert");
    ff().sws_scale(scale, frame->data, frame->linesize, 0, ch, converted->data, converted->linesize);
    const cv::Mat picture(h, w, CV_8UC3, converted->data[0], static_cast<std::size_t>(converted->linesize[0]));
    if (rotation == 90)
      cv::rotate(picture, bgr, cv::ROTATE_90_CLOCKWISE);
    else if (rotation == 180)
      cv::rotate(picture, bgr, cv::ROTATE_180);
    else if (rotation == 270)
      cv::rotate(picture, bgr, cv::ROTATE_90_COUNTERCLOCKWISE);
    else
      picture.copyTo(bgr);
  }
};

VideoFileReader::VideoFileReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  quietByDefault();
  Impl& m = *impl_;
  int rc = ff().avformat_open_input(&m.format, path.c_str(), nullptr, nullptr);
  if (rc < 0) throw VideoFileError("not a video FFmpeg reads (" + ffmpegError(rc) + ")");
  rc = ff().avformat_find_stream_info(m.format, nullptr);
  if (rc < 0) throw VideoFileError("no stream can be read (" + ffmpegError(rc) + ")");
  // The first video stream (as OpenCV's capture chooses).
  for (unsigned i = 0; i < m.format->nb_streams && m.stream < 0; ++i)
    if (m.format->streams[i]->codecpar->codec_type == AVMEDIA_TYPE_VIDEO) m.stream = static_cast<int>(i);
  if (m.stream < 0) throw VideoFileError("no video stream");
  const AVStream* st = m.format->streams[m.stream];
  const AVCodec* codec = ff().avcodec_find_decoder(st->codecpar->codec_id);
  if (codec == nullptr)
    throw VideoFileError("no decoder for its codec (" + std::string(ff().avcodec_get_name(st->codecpar->codec_id)) +
                         ")");
  m.decoder = ff().avcodec_alloc_context3(codec);
  m.packet = ff().av_packet_alloc();
  m.frame = ff().av_frame_alloc();
  if (m.decoder == nullptr || m.packet == nullptr || m.frame == nullptr) throw std::bad_alloc();
  rc = ff().avcodec_parameters_to_context(m.decoder, st->codecpar);
  if (rc >= 0) {
    m.decoder->thread_count = static_cast<int>(std::clamp(sysconf(_SC_NPROCESSORS_ONLN), 1L, 64L));
    rc = ff().avcodec_open2(m.decoder, codec, nullptr);
  }
  if (rc < 0)
    throw VideoFileError("its decoder (" + std::string(codec->name) + ") refuses it (" + ffmpegError(rc) + ")");
  std::size_t size = 0;
  if (const std::uint8_t* matrix = ff().av_stream_get_side_data(st, AV_PKT_DATA_DISPLAYMATRIX, &size);
      matrix != nullptr && size >= 9 * sizeof(std::int32_t)) {
    const double angle = ff().av_display_rotation_get(reinterpret_cast<const std::int32_t*>(matrix));
    if (std::isfinite(angle)) {
      // av_display_rotation_get is counter-clockwise; the picture is shown turned clockwise by its negative.
      const long turn = ((std::lround(-angle) % 360) + 360) % 360;
      if (turn == 90 || turn == 180 || turn == 270) m.rotation = static_cast<int>(turn);
    }
  }
}

VideoFileReader::~VideoFileReader() = default;

double VideoFileReader::fps() const {
  const AVStream* st = impl_->format->streams[impl_->stream];
  // The average rate (OpenCV's), else the base rate (rather than OpenCV's 1 / time base).
  for (const AVRational r : {st->avg_frame_rate, st->r_frame_rate}) {
    if (r.num > 0 && r.den > 0) {
      const double fps = av_q2d(r);
      if (std::isfinite(fps) && fps > 0.0 && fps < 1e6) return fps;
    }
  }
  return 0.0;
}

std::size_t VideoFileReader::declaredFrames() const {
  const AVStream* st = impl_->format->streams[impl_->stream];
  if (st->nb_frames > 0 && st->nb_frames < 1000000000) return static_cast<std::size_t>(st->nb_frames);
  double seconds = 0.0;
  if (impl_->format->duration > 0 && impl_->format->duration != AV_NOPTS_VALUE)
    seconds = static_cast<double>(impl_->format->duration) / AV_TIME_BASE;
  else if (st->duration > 0 && st->duration != AV_NOPTS_VALUE)
    seconds = static_cast<double>(st->duration) * av_q2d(st->time_base);
  const double n = std::floor(seconds * fps() + 0.5);
  return std::isfinite(n) && n > 0.0 && n < 1e9 ? static_cast<std::size_t>(n) : 0;
}

std::string VideoFileReader::fourcc() const {
  const AVCodecParameters* par = impl_->format->streams[impl_->stream]->codecpar;
  const std::string stored = fourccText(par->codec_tag);
  return stored.size() == 4 ? stored : fourccText(ff().av_codec_get_tag(usualTags(), par->codec_id));
}

bool VideoFileReader::read(cv::Mat& bgr) {
  Impl& m = *impl_;
  int refused = 0;
  for (;;) {
    int rc = ff().avcodec_receive_frame(m.decoder, m.frame);
    if (rc == 0) {
      m.convert(bgr);
      ff().av_frame_unref(m.frame);
      return true;
    }
    if (rc == AVERROR_EOF) return false;
    if (rc != AVERROR(EAGAIN)) throw VideoFileError("the decoder fails (" + ffmpegError(rc) + ")");
    if (m.draining) return false;
    // The decoder wants more: the next packet of the stream, or the end.
    rc = ff().av_read_frame(m.format, m.packet);
    if (rc < 0) {
      m.draining = true;
      rc = ff().avcodec_send_packet(m.decoder, nullptr);
      if (rc < 0 && rc != AVERROR_EOF) throw VideoFileError("the decoder fails at the end (" + ffmpegError(rc) + ")");
      continue;
    }
    if (m.packet->stream_index == m.stream) {
      rc = ff().avcodec_send_packet(m.decoder, m.packet);
      if (rc < 0 && rc != AVERROR(EAGAIN)) {
        if (++refused >= 64) {
          ff().av_packet_unref(m.packet);
          throw VideoFileError("the decoder refuses 64 packets in a row (" + ffmpegError(rc) + ")");
        }
      } else {
        refused = 0;
      }
    }
    ff().av_packet_unref(m.packet);
  }
}

// ---------------------------------------------------------------------------------------------
// Writing

struct VideoFileWriter::Impl {
  AVFormatContext* format = nullptr;
  AVCodecContext* encoder = nullptr;
  AVStream* stream = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* scale = nullptr;
  std::int64_t next_pts = 0;
  bool file_open = false, header_written = false, finished = false;

  // The encoder's thread: write() converts a frame's pixels into a free frame of the pool and
  // queues it; the thread encodes the queue in order and writes the packets, then, once finish()
  // sets end_queued, drains the encoder. The first failure stops it and is rethrown by the next
  // write() or finish().
  static constexpr std::size_t kPoolFrames = 3;
  std::vector<AVFrame*> pool;         // every frame made, freed at the end
  std::vector<std::uint8_t*> pixels;  // their planes, packed (OpenCV's layout), not reference-counted:
                                      // the encoder copies what it keeps, as it did one frame at a time
  std::vector<AVFrame*> free_ones;    // frames no one holds
  std::deque<AVFrame*> queued;        // converted, in order, not yet encoded
  bool end_queued = false, stop = false;
  std::exception_ptr failure;
  std::mutex mu;
  std::condition_variable wake;
  std::thread thread;

  ~Impl() {
    if (thread.joinable()) {
      {
        std::lock_guard lock(mu);
        stop = true;
      }
      wake.notify_all();
      thread.join();
    }
    const detail::FfmpegApi* f = detail::loadedFfmpeg();
    if (f == nullptr) return;                                      // nothing of FFmpeg's was made
    if (header_written && !finished) f->av_write_trailer(format);  // an unfinished file, closed; its owner removes it
    if (file_open) f->avio_closep(&format->pb);
    f->sws_freeContext(scale);
    for (AVFrame*& frame : pool) f->av_frame_free(&frame);
    for (std::uint8_t* p : pixels) f->av_free(p);
    f->av_packet_free(&packet);
    f->avcodec_free_context(&encoder);
    f->avformat_free_context(format);
  }

  // Sends `input` (null: the end) and writes every packet the encoder has ready.
  void encode(const AVFrame* input) {
    int rc = ff().avcodec_send_frame(encoder, input);
    if (rc < 0 && !(input == nullptr && rc == AVERROR_EOF))
      throw VideoFileError("the encoder fails (" + ffmpegError(rc) + ")");
    for (;;) {
      rc = ff().avcodec_receive_packet(encoder, packet);
      if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
      if (rc < 0) throw VideoFileError("the encoder fails (" + ffmpegError(rc) + ")");
      ff().av_packet_rescale_ts(packet, encoder->time_base, stream->time_base);
      packet->stream_index = stream->index;
      rc = ff().av_write_frame(format, packet);
      if (rc < 0) throw VideoFileError("cannot write to the file (" + ffmpegError(rc) + ")");
    }
  }

  // The encoder thread's loop: every queued frame encoded in order, then the end.
  void run() {
    for (;;) {
      AVFrame* f = nullptr;
      {
        std::unique_lock lock(mu);
        wake.wait(lock, [&] { return stop || !queued.empty() || end_queued; });
        if (stop) return;
        if (queued.empty()) break;  // the end, everything before it encoded
        f = queued.front();
        queued.pop_front();
      }
      std::exception_ptr error;
      try {
        encode(f);
      } catch (...) {
        error = std::current_exception();
      }
      std::lock_guard lock(mu);
      free_ones.push_back(f);
      failure = error;
      wake.notify_all();
      if (error) return;
    }
    try {
      if (next_pts > 0) encode(nullptr);
    } catch (...) {
      std::lock_guard lock(mu);
      failure = std::current_exception();
    }
  }

  // A frame to convert into: a free one of the pool, once the encoder has handed one back.
  AVFrame* freeFrame() {
    std::unique_lock lock(mu);
    wake.wait(lock, [&] { return failure != nullptr || !free_ones.empty(); });
    if (failure) std::rethrow_exception(failure);
    AVFrame* f = free_ones.back();
    free_ones.pop_back();
    return f;
  }
};

namespace {

// The frame rate as a fraction: fps to 3 decimals, not reduced (29.97 is 2997/100), as OpenCV's
// writer gives it; an encoder with a list of rates gets the closest of them.
AVRational frameRate(double fps, const AVCodec* codec) {
  int base = 1;
  int num = static_cast<int>(std::floor(fps + 0.5));  // fps > 0: OpenCV's (int)(fps + 0.5)
  while (std::abs(static_cast<double>(num) / base - fps) > 0.001 && base < 100000) {
    base *= 10;
    num = static_cast<int>(std::floor(fps * base + 0.5));
  }
  AVRational rate{num, base};
  if (const AVRational* listed = codec->supported_framerates; listed != nullptr && listed->num != 0) {
    AVRational best = *listed;
    for (; listed->num != 0; ++listed)
      if (std::abs(av_q2d(ff().av_sub_q(rate, *listed))) < std::abs(av_q2d(ff().av_sub_q(rate, best)))) best = *listed;
    rate = best;
  }
  return rate;
}

}  // namespace

VideoFileWriter::VideoFileWriter(const std::string& path, const std::string& fourcc, double fps, int width, int height)
    : impl_(std::make_unique<Impl>()) {
  quietByDefault();
  Impl& m = *impl_;
  if (!(std::isfinite(fps) && fps > 0.0 && fps <= 1000.0)) throw VideoFileError("a frame rate not in (0, 1000]");
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw VideoFileError("a frame size not in 1..16384");
  int rc = ff().avformat_alloc_output_context2(&m.format, nullptr, nullptr, path.c_str());
  if (rc < 0 || m.format == nullptr) throw VideoFileError("a container FFmpeg does not write (use .mp4, .mkv or .avi)");
  const AVCodecID id = codecOf(fourcc);
  const AVCodec* codec = id == AV_CODEC_ID_NONE ? nullptr : ff().avcodec_find_encoder(id);
  if (codec == nullptr) throw VideoFileError("no encoder for the codec " + fourcc);
  // Matroska's list leaves out FFVHUFF, which it stores (as FFmpeg's own command does) under its
  // Video for Windows FourCC.
  const bool vfw_in_matroska = id == AV_CODEC_ID_FFVHUFF && std::strcmp(m.format->oformat->name, "matroska") == 0;
  if (!vfw_in_matroska && ff().avformat_query_codec(m.format->oformat, id, FF_COMPLIANCE_NORMAL) != 1)
    throw VideoFileError("the container does not take the codec " + fourcc);
  m.stream = ff().avformat_new_stream(m.format, nullptr);
  m.encoder = ff().avcodec_alloc_context3(codec);
  m.packet = ff().av_packet_alloc();
  if (m.stream == nullptr || m.encoder == nullptr || m.packet == nullptr) throw std::bad_alloc();
  // The settings of OpenCV 4.6's FFmpeg writer, so a video comes out as it did through OpenCV.
  m.format->max_delay = static_cast<int>(0.7 * AV_TIME_BASE);
  AVCodecContext& c = *m.encoder;
  std::uint32_t tag = fourccCode(fourcc);
  if (const AVCodecTag* const* muxer = m.format->oformat->codec_tag;
      muxer != nullptr && ff().av_codec_get_id(muxer, tag) != id)
    if (const unsigned usual = ff().av_codec_get_tag(muxer, id); usual != 0) tag = usual;
  if (id == AV_CODEC_ID_FFVHUFF) tag = fourccCode("FFVH");  // its one spelling, whatever the case given
  c.codec_tag = tag;
  c.qmin = 3;
  c.width = width;
  c.height = height;
  const AVRational rate = frameRate(fps, codec);
  c.time_base = av_inv_q(rate);
  // Bit rate: B = fps x width x height (x 3 for Motion JPEG), 1.5 B for the codec, then B / 2 more.
  const double nominal =
      std::min((id == AV_CODEC_ID_MJPEG ? 3.0 : 1.0) * fps * width * height, std::numeric_limits<int>::max() / 2.0);
  const auto b = static_cast<std::int64_t>(std::floor(nominal + 0.5));
  c.bit_rate = std::min<std::int64_t>(b + b / 2, std::numeric_limits<int>::max());
  c.gop_size = 12;
  c.pix_fmt = id == AV_CODEC_ID_MJPEG     ? AV_PIX_FMT_YUVJ420P
              : id == AV_CODEC_ID_FFV1    ? AV_PIX_FMT_BGRA
              : id == AV_CODEC_ID_FFVHUFF ? AV_PIX_FMT_GBRP
                                          : AV_PIX_FMT_YUV420P;
  // FFVHUFF (not one of OpenCV's): lossless, planar RGB with the median predictor, the smallest of
  // its fast settings (1.2x FFV1's size, 4x faster to write, 2.7x faster to read).
  if (id == AV_CODEC_ID_FFVHUFF) ff().av_opt_set(c.priv_data, "pred", "median", 0);
  if (id == AV_CODEC_ID_H264) {
    c.gop_size = -1;
    c.qmin = -1;
    c.bit_rate = 0;
    ff().av_opt_set(c.priv_data, "crf", "23", 0);
  }
  c.bit_rate =
      std::min<std::int64_t>(c.bit_rate + static_cast<std::int64_t>(nominal / 2), std::numeric_limits<int>::max());
  c.bit_rate_tolerance = static_cast<int>(c.bit_rate);
  if ((m.format->oformat->flags & AVFMT_GLOBALHEADER) != 0) c.flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  rc = ff().avcodec_open2(m.encoder, codec, nullptr);
  if (rc < 0)
    throw VideoFileError("the encoder " + std::string(codec->name) + " refuses these frames (" + ffmpegError(rc) + ")");
  rc = ff().avcodec_parameters_from_context(m.stream->codecpar, m.encoder);
  if (rc < 0) throw VideoFileError("the encoder's parameters (" + ffmpegError(rc) + ")");
  m.stream->time_base = c.time_base;
  m.stream->avg_frame_rate = rate;
  if ((m.format->oformat->flags & AVFMT_NOFILE) == 0) {
    rc = ff().avio_open(&m.format->pb, path.c_str(), AVIO_FLAG_WRITE);
    if (rc < 0) throw VideoFileError("cannot create the file (" + ffmpegError(rc) + ")");
    m.file_open = true;
  }
  rc = ff().avformat_write_header(m.format, nullptr);
  if (rc < 0) throw VideoFileError("cannot write the container's header (" + ffmpegError(rc) + ")");
  m.header_written = true;
  for (std::size_t k = 0; k < Impl::kPoolFrames; ++k) {
    AVFrame* f = ff().av_frame_alloc();
    if (f == nullptr) throw std::bad_alloc();
    m.pool.push_back(f);
    f->format = c.pix_fmt;
    f->width = width;
    f->height = height;
    const int bytes = ff().av_image_get_buffer_size(c.pix_fmt, width, height, 1);
    auto* planes = bytes > 0 ? static_cast<std::uint8_t*>(ff().av_malloc(static_cast<std::size_t>(bytes))) : nullptr;
    if (planes == nullptr) throw std::bad_alloc();
    m.pixels.push_back(planes);
    if (ff().av_image_fill_arrays(f->data, f->linesize, planes, c.pix_fmt, width, height, 1) < 0)
      throw std::bad_alloc();
    m.free_ones.push_back(f);
  }
  m.scale = ff().sws_getContext(width, height, AV_PIX_FMT_BGR24, width, height, c.pix_fmt, SWS_BICUBIC, nullptr,
                                nullptr, nullptr);
  if (m.scale == nullptr) throw VideoFileError("swscale cannot convert BGR to the encoder's pixel format");
}

VideoFileWriter::~VideoFileWriter() = default;

void VideoFileWriter::write(const cv::Mat& bgr) {
  Impl& m = *impl_;
  if (bgr.type() != CV_8UC3 || bgr.cols != m.encoder->width || bgr.rows != m.encoder->height)
    throw std::logic_error("a video frame of another size or type than the writer's");
  if (m.finished) throw std::logic_error("a video frame after finish()");
  if (!m.thread.joinable()) m.thread = std::thread([&m] { m.run(); });
  AVFrame* f = m.freeFrame();
  const std::uint8_t* const planes[4] = {bgr.data, nullptr, nullptr, nullptr};
  const int strides[4] = {static_cast<int>(bgr.step[0]), 0, 0, 0};
  ff().sws_scale(m.scale, planes, strides, 0, bgr.rows, f->data, f->linesize);
  f->pts = m.next_pts++;
  {
    std::lock_guard lock(m.mu);
    m.queued.push_back(f);
  }
  m.wake.notify_all();
}

void VideoFileWriter::finish() {
  Impl& m = *impl_;
  if (m.finished) return;
  if (m.thread.joinable()) {
    {
      std::lock_guard lock(m.mu);
      m.end_queued = true;
    }
    m.wake.notify_all();
    m.thread.join();
  }
  if (m.failure) std::rethrow_exception(m.failure);  // also at a second call: the file is not whole
  m.finished = true;
  const int rc = ff().av_write_trailer(m.format);
  if (rc < 0) throw VideoFileError("cannot finish the file (" + ffmpegError(rc) + ")");
  if (m.file_open) {
    m.file_open = false;
    if (ff().avio_closep(&m.format->pb) < 0) throw VideoFileError("cannot close the file");
  }
}

}  // namespace kccd::overlay
