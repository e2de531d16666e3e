// A small stand-in for libFuzzer's driver, so every fuzz target also runs in the normal (GCC) build
// and its test suite: `fuzz_<target>_replay [-seconds=S] [-seed=N] FILE|DIR...`
//  1. runs each corpus file as is, and hostile variants of it (wrapped in 100,000 brackets, numbers
//     replaced by 1e999 and -1e30, cut in half, NUL bytes inserted) and, for three of them, after an
//     object's 50,000 distinct keys (each under a 10 s bound);
//  2. then, for S seconds (default 2), random mutations of random corpus entries (bit flips, byte
//     insertions and deletions, repeated slices, splices of two entries, interesting tokens).
// It is not coverage-guided (use the libFuzzer build, scripts/fuzz, for that); it catches
// regressions of known hostile shapes quickly. Prints the number of executions; any crash or
// escaped exception ends the process abnormally.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

// an escaped exception is a finding: the input is saved (like libFuzzer's artifacts) and the
// process aborts
void run(const std::string& input) {
  try {
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
  } catch (const std::exception& e) {
    const std::string file = "replay-finding-" + std::to_string(std::hash<std::string>{}(input));
    std::ofstream(file, std::ios::binary).write(input.data(), static_cast<std::streamsize>(input.size()));
    std::fprintf(stderr, "finding: %s (input of %zu bytes saved to %s)\n", e.what(), input.size(), file.c_str());
    std::abort();
  }
}

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string replace_numbers(const std::string& s, const std::string& with) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    if (s[i] >= '0' && s[i] <= '9' && (i == 0 || s[i - 1] == ':' || s[i - 1] == ' ' || s[i - 1] == '[' || s[i - 1] == ',')) {
      while (i < s.size() && ((s[i] >= '0' && s[i] <= '9') || s[i] == '.' || s[i] == 'e' || s[i] == '-')) ++i;
      out += with;
    } else {
      out += s[i++];
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 2.0;
  std::uint64_t seed = 20260718;
  std::vector<std::string> corpus;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("-seconds=", 0) == 0) { seconds = std::stod(a.substr(9)); continue; }
    if (a.rfind("-seed=", 0) == 0) { seed = std::stoull(a.substr(6)); continue; }
    const std::filesystem::path p(a);
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(p))
        if (e.is_regular_file()) corpus.push_back(read(e.path()));
    } else if (std::filesystem::is_regular_file(p)) {
      corpus.push_back(read(p));
    } else {
      std::fprintf(stderr, "no such corpus file or directory: %s\n", a.c_str());
      return 2;
    }
  }
  if (corpus.empty()) corpus.push_back("{}");
  std::uint64_t executions = 0;
  const std::string open(100000, '['), close(100000, ']');
  for (const std::string& c : corpus) {
    for (const std::string& v : {c, open + c + close, "{\"a\":" + open + close + "," + c.substr(c.empty() ? 0 : 1),
                                 replace_numbers(c, "1e999"), replace_numbers(c, "-1e30"), c.substr(0, c.size() / 2),
                                 c.substr(0, c.size() / 3) + std::string(1, '\0') + c.substr(c.size() / 3)}) {
      run(v);
      ++executions;
    }
  }
  // an object of 50,000 distinct keys (with the entry's own fields after them, and then a repeat of
  // the first key), each under a time bound: a duplicate-key check that compares every key with all
  // before it takes minutes here (1.25e9 comparisons), one hash set per object milliseconds
  constexpr int kManyKeys = 50000;
  constexpr double kManyKeysSeconds = 10.0;
  std::string keys = "{";
  for (int k = 0; k < kManyKeys; ++k) keys += "\"k" + std::to_string(k) + "\":0,";
  std::vector<std::string> many = {keys + "\"k0\":1}"};
  for (std::size_t i = 0; i < corpus.size() && i < 3; ++i) {  // three seeds: each costs a 600 KB parse
    const std::string& c = corpus[i];
    many.push_back(keys + (!c.empty() && c.front() == '{' ? c.substr(1) : "\"x\":" + c + "}"));
  }
  for (const std::string& v : many) {
    const auto start = std::chrono::steady_clock::now();
    run(v);
    ++executions;
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (took > kManyKeysSeconds) {
      std::fprintf(stderr, "finding: an object of %d keys took %.1f s (more than %.0f s: quadratic in its keys?)\n", kManyKeys, took,
                   kManyKeysSeconds);
      std::abort();
    }
  }
  static const char* kTokens[] = {"[", "]", "{", "}", "\"", ":", ",", "1e999", "-1e999", "1e30", "NaN", "nan", "-0",
                                  "null", "true", "18446744073709551616", "<", ">", "/>", "</", "<joint", "<link",
                                  "\n", "- ", ": ", "&a ", "*a", "\\u0000", "9999999999"};
  std::mt19937_64 rng(seed);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    std::string s = corpus[rng() % corpus.size()];
    const int edits = 1 + static_cast<int>(rng() % 8);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = s.empty() ? 0 : rng() % (s.size() + 1);
      switch (rng() % 6) {
        case 0: if (!s.empty() && at < s.size()) s[at] = static_cast<char>(s[at] ^ (1u << (rng() % 8))); break;
        case 1: s.insert(at, 1, static_cast<char>(rng() % 256)); break;
        case 2: if (at < s.size()) s.erase(at, 1 + rng() % std::min<std::size_t>(16, s.size() - at)); break;
        case 3: s.insert(at, kTokens[rng() % std::size(kTokens)]); break;
        case 4: if (at < s.size()) { const std::string piece = s.substr(at, 1 + rng() % 8); for (int k = 0; k < 1 + static_cast<int>(rng() % 64); ++k) s.insert(at, piece); } break;
        default: { const std::string& o = corpus[rng() % corpus.size()]; if (!o.empty()) s = s.substr(0, at) + o.substr(rng() % o.size()); }
      }
    }
    if (s.size() > (1u << 20)) s.resize(1u << 20);
    run(s);
    ++executions;
  }
  std::printf("%llu executions, no crash\n", static_cast<unsigned long long>(executions));
  return 0;
}
