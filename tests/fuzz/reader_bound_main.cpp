// The time bound on a reader: runs one fuzz target's entry point (LLVMFuzzerTestOneInput, the
// reader as the fuzzer calls it) on its seed corpus and on adversarial inputs made from it, up to
// 1 MiB each, and fails when any one input takes longer than the bound: a reader must never spin.
//   reader_bound_NAME [--bound SECONDS] FILE_OR_DIR...
// A watchdog thread ends the process (exit 1, naming the input) the moment an input passes the
// bound, so a hang is reported instead of stalling the suite. Prints the slowest inputs.
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

struct Input {
  std::string name;
  std::string bytes;
};

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// `unit` repeated up to `size` bytes.
std::string tile(const std::string& unit, std::size_t size = kMiB) {
  std::string out;
  if (unit.empty()) return out;
  out.reserve(size);
  while (out.size() + unit.size() <= size) out += unit;
  return out;
}

// Inputs built from a seed: the seed itself, tiled to 1 MiB, its middle line repeated to 1 MiB,
// a 1 MiB run of one byte in its middle, and cut at a third and two thirds.
void derived(const std::string& name, const std::string& seed, std::vector<Input>& out) {
  out.push_back({name, seed});
  if (seed.empty()) return;
  out.push_back({name + " tiled to 1 MiB", tile(seed)});
  const std::size_t mid = seed.size() / 2;
  const std::size_t begin = seed.rfind('\n', mid) == std::string::npos ? 0 : seed.rfind('\n', mid) + 1;
  const std::size_t end = std::min(seed.find('\n', mid), seed.size() - 1) + 1;
  const std::string line = seed.substr(begin, end - begin);
  if (seed.size() < kMiB)
    out.push_back({name + " with its middle line repeated to 1 MiB",
                   seed.substr(0, begin) + tile(line, kMiB - seed.size()) + seed.substr(begin)});
  out.push_back(
      {name + " with 1 MiB of 'a' in its middle", seed.substr(0, mid) + std::string(kMiB, 'a') + seed.substr(mid)});
  out.push_back(
      {name + " with 1 MiB of '9' in its middle", seed.substr(0, mid) + std::string(kMiB, '9') + seed.substr(mid)});
  out.push_back({name + " cut at 1/3", seed.substr(0, seed.size() / 3)});
  out.push_back({name + " cut at 2/3", seed.substr(0, 2 * seed.size() / 3)});
}

// Inputs of 1 MiB that stress parsers whatever the format: nesting, long tokens, many lines,
// random bytes.
void generic(std::vector<Input>& out) {
  const std::size_t half = kMiB / 2;
  out.push_back({"1 MiB of '['", std::string(kMiB, '[')});
  out.push_back({"1 MiB of '{'", std::string(kMiB, '{')});
  out.push_back({"nested YAML/JSON lists, 1 MiB", std::string(half, '[') + std::string(half, ']')});
  out.push_back({"nested XML elements, 1 MiB", tile("<a>", half) + tile("</a>", half)});
  out.push_back({"nested YAML block lists, 1 MiB", [] {
                   std::string s;
                   for (std::size_t depth = 0; s.size() < kMiB - 4096; ++depth)
                     s += std::string(depth % 2000, ' ') + "- \n";
                   return s;
                 }()});
  out.push_back({"YAML anchors and aliases, 1 MiB", [] {
                   std::string s = "a0: &a0 [1, 2]\n";
                   for (int i = 1; s.size() < kMiB - 64; ++i)
                     s += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) +
                          ", *a" + std::to_string(i - 1) + "]\n";
                   return s;
                 }()});
  out.push_back({"one key repeated, 1 MiB", tile("key: 1\n")});
  out.push_back({"1 MiB of newlines", std::string(kMiB, '\n')});
  out.push_back({"1 MiB of commas", std::string(kMiB, ',')});
  out.push_back({"1 MiB of '-'", std::string(kMiB, '-')});
  out.push_back({"1 MiB of quotes", std::string(kMiB, '"')});
  out.push_back({"1 MiB of '9'", std::string(kMiB, '9')});
  out.push_back({"1 MiB of zero bytes", std::string(kMiB, '\0')});
  out.push_back({"1 MiB of 0xFF", std::string(kMiB, '\xff')});
  out.push_back({"1 MiB of random bytes", [] {
                   std::mt19937 rng(1);
                   std::string s(kMiB, '\0');
                   for (char& c : s) c = static_cast<char>(rng() & 0xFF);
                   return s;
                 }()});
  out.push_back({"1 MiB of random text lines", [] {
                   std::mt19937 rng(2);
                   const std::string alphabet = "abc019.,:;-_ []{}<>\"'&*!%#/\\=\t\n";
                   std::string s(kMiB, ' ');
                   for (char& c : s) c = alphabet[rng() % alphabet.size()];
                   return s;
                 }()});
}

struct Watchdog {
  std::mutex m;
  std::condition_variable cv;
  const Input* current = nullptr;
  std::chrono::steady_clock::time_point started;
  bool done = false;
};

}  // namespace

int main(int argc, char** argv) {
  double bound = 60.0;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--bound" && i + 1 < argc)
      bound = std::atof(argv[++i]);
    else
      paths.push_back(a);
  }
  const char* name = argv[0];
  if (const char* slash = std::strrchr(argv[0], '/')) name = slash + 1;
  std::vector<Input> inputs;
  for (const std::string& p : paths) {
    std::vector<std::filesystem::path> files;
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::directory_iterator(p))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
    } else {
      files.push_back(p);
    }
    for (const auto& f : files) derived(f.filename().string(), readFile(f), inputs);
  }
  generic(inputs);

  Watchdog dog;
  std::thread watcher([&] {
    std::unique_lock<std::mutex> lock(dog.m);
    while (!dog.done) {
      if (dog.current == nullptr) {
        dog.cv.wait(lock);
        continue;
      }
      const Input* watched = dog.current;
      const auto deadline = dog.started + std::chrono::duration<double>(bound);
      if (dog.cv.wait_until(lock, deadline, [&] { return dog.done || dog.current != watched; })) continue;
      std::fprintf(stderr, "%s: FAILED: the reader ran past the bound of %g s on '%s' (%zu bytes): a hang\n", name,
                   bound, watched->name.c_str(), watched->bytes.size());
      std::fflush(stderr);
      std::_Exit(1);
    }
  });
  std::vector<std::pair<double, const Input*>> times;
  double total = 0.0;
  const bool verbose = std::getenv("KCCD_READER_BOUND_VERBOSE") != nullptr;  // each input named before it runs
  for (const Input& in : inputs) {
    if (verbose) std::fprintf(stderr, "%s: %s (%zu bytes)\n", name, in.name.c_str(), in.bytes.size());
    {
      const std::lock_guard<std::mutex> lock(dog.m);
      dog.current = &in;
      dog.started = std::chrono::steady_clock::now();
    }
    dog.cv.notify_all();
    const auto start = std::chrono::steady_clock::now();
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(in.bytes.data()), in.bytes.size());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    times.emplace_back(s, &in);
    total += s;
    {
      const std::lock_guard<std::mutex> lock(dog.m);
      dog.current = nullptr;
    }
    dog.cv.notify_all();
  }
  {
    const std::lock_guard<std::mutex> lock(dog.m);
    dog.done = true;
  }
  dog.cv.notify_all();
  watcher.join();
  std::sort(times.begin(), times.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::printf("%s: %zu inputs (up to 1 MiB) in %.3f s, each within the bound of %g s; slowest:\n", name, inputs.size(),
              total, bound);
  for (std::size_t i = 0; i < std::min<std::size_t>(3, times.size()); ++i)
    std::printf("  %8.3f s  %s (%zu bytes)\n", times[i].first, times[i].second->name.c_str(),
                times[i].second->bytes.size());
  return 0;
}
