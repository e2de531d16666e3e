#include "actionshift/eval/store.hpp"

#include "actionshift/eval/resolve.hpp"

#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/provenance.hpp"
#include "actionshift/eval/statistics.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>
#include <openssl/evp.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <set>
#include <stdexcept>

namespace actionshift::eval {

namespace {

using nlohmann::json;

std::string errno_text() { return std::strerror(errno); }

std::string read_fd(int fd, const std::string& path) {
  std::string out;
  char buf[1 << 16];
  off_t off = 0;
  for (;;) {
    const ssize_t n = ::pread(fd, buf, sizeof buf, off);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(path, "", "read failed: " + errno_text());
    if (n == 0) break;
    out.append(buf, static_cast<std::size_t>(n));
    off += n;
  }
  return out;
}

std::string hex_digest(const unsigned char* d, std::size_t n) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out(2 * n, '0');
  for (std::size_t i = 0; i < n; ++i) {
    out[2 * i] = kHex[d[i] >> 4];
    out[2 * i + 1] = kHex[d[i] & 0xF];
  }
  return out;
}

// an integer ≥ 0 of a summary, else a one-line error naming the key
std::int64_t summary_count(const json& j, const char* key, const std::string& path) {
  if (!j.contains(key)) throw InputError(path, key, "missing: not a complete job summary (truncated?)");
  const json& v = j.at(key);
  if (v.is_number_unsigned() && v.get<std::uint64_t>() <= static_cast<std::uint64_t>(INT64_MAX)) return v.get<std::int64_t>();
  if (v.is_number_integer() && v.get<std::int64_t>() >= 0) return v.get<std::int64_t>();
  throw InputError(path, key, "expected an integer >= 0 (got " + json_for_message(v) + ")");
}

}  // namespace

std::optional<std::string> records_sha256(std::string_view bytes, std::int64_t n) {
  if (n < 0) return std::nullopt;
  std::size_t end = 0;
  for (std::int64_t k = 0; k < n; ++k) {
    const std::size_t nl = bytes.find('\n', end);
    if (nl == std::string_view::npos) return std::nullopt;
    end = nl + 1;
  }
  return sha256_hex(bytes.substr(0, end));
}

CheckedSummary parse_job_summary(std::string_view text, const std::string& path, const std::string& id) {
  const json j = parse_json_input(text, path);  // a truncated summary is not JSON: a one-line error
  if (!j.is_object()) throw InputError(path, "", "not a job summary (expected a JSON object)");
  CheckedSummary s;
  s.path = path;
  if (!j.contains("schema_version") || !j.at("schema_version").is_string())
    throw InputError(path, "schema_version", "missing: not a job summary");
  s.schema_version = j.at("schema_version").get<std::string>();
  if (s.schema_version != kJobSummarySchemaVersion && s.schema_version != "1.0")
    throw InputError(path, "schema_version", "unsupported job summary schema " + quote_input(s.schema_version, '"') + " (expected \"2.0\" or \"1.0\")");
  const bool v2 = s.schema_version == kJobSummarySchemaVersion;
  if (v2) {
    static const std::set<std::string> keys = {
        "schema_version", "job_id", "job", "episodes_requested", "episodes_done", "complete", "episodes_run", "wall_time_s",
        "message", "provenance", "records_sha256", "success_once", "success_at_end", "mean_return", "mean_steps",
        "mean_probe_steps", "mean_probe_displacement", "episodes_with_safety_flags", "safety_flag_counts", "per_contract"};
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!keys.count(it.key())) throw InputError(path, it.key(), "unknown key in a job summary");
    for (const auto& k : keys)
      if (!j.contains(k)) throw InputError(path, k, "missing: not a complete job summary (truncated?)");
  }
  if (!j.contains("job_id") || !j.at("job_id").is_string() || j.at("job_id").get<std::string>() != id)
    throw InputError(path, "job_id", "is not " + quote_input(id, '"') + ", the job its file name names");
  if (!j.contains("job")) throw InputError(path, "job", "missing: not a complete job summary (truncated?)");
  s.job = job_from_json(j.at("job"), path + ": job");
  if (job_id(s.job) != id) throw InputError(path, "job", "is the spec of another job (its id is " + job_id(s.job) + ")");
  const std::int64_t requested = summary_count(j, "episodes_requested", path);
  if (requested != s.job.episodes)
    throw InputError(path, "episodes_requested", "is " + std::to_string(requested) + ", not the job's " + std::to_string(s.job.episodes));
  s.episodes_done = summary_count(j, "episodes_done", path);
  if (s.episodes_done > requested)
    throw InputError(path, "episodes_done", "is more than the job's " + std::to_string(requested) + " episodes");
  if (!j.contains("complete") || !j.at("complete").is_boolean() || j.at("complete").get<bool>() != (s.episodes_done == requested))
    throw InputError(path, "complete", "does not say whether episodes_done equals episodes_requested");
  if (v2) {
    const json& h = j.at("records_sha256");
    if (!h.is_string() || !is_sha256_hex(h.get<std::string>()))
      throw InputError(path, "records_sha256", "expected 64 lowercase hex digits (got " + json_for_message(h) + ")");
    s.records_sha256 = h.get<std::string>();
  }
  const auto successes = [&](const char* key) -> std::int64_t {
    if (!j.contains(key)) throw InputError(path, key, "missing: not a complete job summary (truncated?)");
    const json& w = j.at(key);
    if (s.episodes_done == 0) {
      if (!w.is_null()) throw InputError(path, key, "must be null when no episode is done");
      return 0;
    }
    if (!w.is_object()) throw InputError(path, key, "expected a Wilson interval object (got " + json_for_message(w) + ")");
    const std::string field = std::string(key);
    if (summary_count(w, "total", path + ": " + field) != s.episodes_done)
      throw InputError(path, field + ".total", "is not episodes_done (" + std::to_string(s.episodes_done) + ")");
    const std::int64_t k = summary_count(w, "successes", path + ": " + field);
    if (k > s.episodes_done) throw InputError(path, field + ".successes", "is more than episodes_done");
    return k;
  };
  s.successes_once = successes("success_once");
  s.successes_at_end = successes("success_at_end");
  s.episodes_with_safety_flags = summary_count(j, "episodes_with_safety_flags", path);
  return s;
}

void check_records_hash(const CheckedSummary& s, const std::string& jsonl_path, std::string_view bytes) {
  const std::int64_t lines = static_cast<std::int64_t>(std::count(bytes.begin(), bytes.end(), '\n'));
  if (lines < s.episodes_done)
    throw InputError(jsonl_path, "records_sha256",
                     "the records do not match the summary's hash: the file holds " + std::to_string(lines) +
                         " complete records but " + std::filesystem::path(s.path).filename().string() + " covers " +
                         std::to_string(s.episodes_done) + " (records removed after the job ran?)");
  if (!s.records_sha256) return;  // a 1.0 summary has no hash: only its counts are checked
  const std::string got = *records_sha256(bytes, s.episodes_done);
  if (got != *s.records_sha256)
    throw InputError(jsonl_path, "records_sha256",
                     "the records do not match the summary's hash (" + std::filesystem::path(s.path).filename().string() +
                         ": " + s.records_sha256->substr(0, 16) + "… of the first " + std::to_string(s.episodes_done) +
                         " records; the file's: " + got.substr(0, 16) + "…): edited after the job ran? run the job again from scratch (remove both files)");
}

void check_records_against_summary(const CheckedSummary& s, const std::string& jsonl_path, std::string_view bytes,
                                   const std::vector<EpisodeRecord>& records) {
  check_records_hash(s, jsonl_path, bytes);
  if (static_cast<std::int64_t>(records.size()) < s.episodes_done)
    throw InputError(jsonl_path, "records_sha256",
                     "the records do not match the summary's hash: " + std::to_string(records.size()) + " records, but " +
                         std::filesystem::path(s.path).filename().string() + " covers " + std::to_string(s.episodes_done));
  std::int64_t once = 0, at_end = 0, flagged = 0;
  for (std::int64_t i = 0; i < s.episodes_done; ++i) {
    const EpisodeRecord& r = records[static_cast<std::size_t>(i)];
    once += r.success_once;
    at_end += r.success_at_end;
    flagged += r.safety_flags.empty() ? 0 : 1;
  }
  const auto differ = [&](const char* field, std::int64_t says, std::int64_t is) {
    if (says == is) return;
    // with a matching hash only the summary can be wrong; a 1.0 summary cannot tell which of the two was edited
    const bool hashed = s.records_sha256.has_value();
    throw InputError(hashed ? s.path : jsonl_path, field,
                     (hashed ? "is " + std::to_string(says) + " but the records it covers hold " + std::to_string(is) +
                                   ": the summary is corrupt (remove it and run the job again to rewrite it)"
                             : "the records do not match the summary (" + std::filesystem::path(s.path).filename().string() + " says " +
                                   std::to_string(says) + ", the first " + std::to_string(s.episodes_done) + " records hold " +
                                   std::to_string(is) + "): edited after the job ran?"));
  };
  differ("success_once.successes", s.successes_once, once);
  differ("success_at_end.successes", s.successes_at_end, at_end);
  differ("episodes_with_safety_flags", s.episodes_with_safety_flags, flagged);
}

void check_record_belongs(const EpisodeRecord& r, const JobSpec& job, const std::string& id,
                          std::int64_t episode_index, const std::string& src) {
  auto differs = [&](const char* field, const std::string& got, const std::string& want) {
    throw InputError(src, field, "record belongs to another job (got " + quote_input(got, '"') + ", expected " + quote_input(want, '"') + ")");
  };
  if (r.job_id != id) differs("job_id", r.job_id, id);
  if (r.episode_index != episode_index)
    throw InputError(src, "episode_index", "records must be episodes 0..k-1 in order (got " +
                                               std::to_string(r.episode_index) + ", expected " +
                                               std::to_string(episode_index) + ")");
  if (r.task != job.task) differs("task", r.task, job.task);
  if (r.split != job.split.name) differs("split", r.split, job.split.name);
  if (r.method != job.method) differs("method", r.method, job.method);
  if (const std::string v = method_variant(job); r.method_variant != v) differs("method_variant", r.method_variant, v);
  if (r.seed != job.seed) differs("seed", std::to_string(r.seed), std::to_string(job.seed));
  if (r.backbone != job.backbone.name) differs("backbone", r.backbone, job.backbone.name);
  if (r.backbone_sha256 != job.backbone.sha256) differs("backbone_sha256", r.backbone_sha256, job.backbone.sha256);
  if (r.profile != job.profile) differs("profile", r.profile, job.profile);
  if (r.obs_noise != job.obs_noise) differs("obs_noise", std::to_string(r.obs_noise), std::to_string(job.obs_noise));
  const auto slot = episode_slot(job.seed, job.split.contracts, episode_index);
  if (r.contract_index != slot.contract_index)
    throw InputError(src, "contract_index", "expected " + std::to_string(slot.contract_index) + " for episode " +
                                                std::to_string(episode_index) + " (got " +
                                                std::to_string(r.contract_index) + ")");
}

// SHA-256 of the bytes of the records held, updated as they are read and appended
struct ResultStore::Digest {
  EVP_MD_CTX* ctx{EVP_MD_CTX_new()};
  Digest() {
    if (!ctx || EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr) != 1) throw std::runtime_error("sha256: OpenSSL EVP init failed");
  }
  ~Digest() { EVP_MD_CTX_free(ctx); }
  Digest(const Digest&) = delete;
  Digest& operator=(const Digest&) = delete;
  void update(std::string_view bytes) {
    if (EVP_DigestUpdate(ctx, bytes.data(), bytes.size()) != 1) throw std::runtime_error("sha256: OpenSSL EVP update failed");
  }
  std::string hex() const {
    EVP_MD_CTX* copy = EVP_MD_CTX_new();
    unsigned char d[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    const bool ok = copy && EVP_MD_CTX_copy_ex(copy, ctx) == 1 && EVP_DigestFinal_ex(copy, d, &len) == 1 && len == 32;
    EVP_MD_CTX_free(copy);
    if (!ok) throw std::runtime_error("sha256: OpenSSL EVP final failed");
    return hex_digest(d, len);
  }
};

std::string ResultStore::records_sha256() const {
  if (!digest_) throw std::runtime_error("ResultStore::records_sha256: store is closed");
  return digest_->hex();
}

ResultStore ResultStore::open(const std::string& out_dir, const JobSpec& job, const StoreOptions& options) {
  ResultStore s;
  s.job_ = job;
  s.id_ = eval::job_id(job);  // validates the job
  s.fsync_ = options.fsync;
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "", "cannot create output directory: " + ec.message());
  s.path_ = (std::filesystem::path(out_dir) / jsonl_file_name(s.id_)).string();
  s.summary_path_ = (std::filesystem::path(out_dir) / summary_file_name(s.id_)).string();

  // open without truncation and take the job's lock before reading anything
  // O_NOFOLLOW: a symbolic link at <id>.jsonl would make the job append to (and repair) a file outside --out
  s.fd_ = ::open(s.path_.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (s.fd_ < 0 && errno == ELOOP)
    throw InputError(s.path_, "", "is a symbolic link: a results file must be a regular file inside the results directory");
  if (s.fd_ < 0) throw InputError(s.path_, "", "cannot open results file: " + errno_text());
  struct stat st{};
  if (::fstat(s.fd_, &st) != 0 || !S_ISREG(st.st_mode))
    throw InputError(s.path_, "", "not a regular file (a device, FIFO or directory cannot hold results)");
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxInputFileBytes * 4)
    throw InputError(s.path_, "", "results file too large (" + std::to_string(st.st_size) + " bytes)");
  if (::flock(s.fd_, LOCK_EX | LOCK_NB) != 0)
    throw InputError(s.path_, "", "another process is running this job (results file is locked)");

  const std::string bytes = read_fd(s.fd_, s.path_);
  // split into lines; the last piece is torn if it has no newline
  std::vector<std::pair<std::size_t, std::size_t>> lines;  // [begin, end) without the newline
  std::size_t start = 0;
  bool unterminated = false;
  while (start < bytes.size()) {
    const std::size_t nl = bytes.find('\n', start);
    if (nl == std::string::npos) {
      lines.emplace_back(start, bytes.size());
      unterminated = true;
      break;
    }
    lines.emplace_back(start, nl);
    start = nl + 1;
  }

  // the job's summary vouches for its first records: they must be the bytes it hashed, before anything
  // is repaired (an edited last record must not pass for a torn write and be cut away). A new or empty
  // file is run from scratch and gets a new summary
  std::optional<CheckedSummary> summary;
  if (std::error_code sec; !bytes.empty() && std::filesystem::symlink_status(s.summary_path_, sec).type() != std::filesystem::file_type::not_found) {
    summary = parse_job_summary(detail::read_file(s.summary_path_), s.summary_path_, s.id_);
    check_records_hash(*summary, s.path_, bytes);
  }

  // validate everything first; only a torn tail may be repaired, and only after all else passed
  std::size_t keep_bytes = bytes.size();
  std::vector<EpisodeRecord> records;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const bool last = i + 1 == lines.size();
    const std::string src = s.path_ + ":" + std::to_string(i + 1);
    const std::string_view text = std::string_view(bytes).substr(lines[i].first, lines[i].second - lines[i].first);
    if (last && unterminated) {
      keep_bytes = lines[i].first;
      break;
    }
    // a complete (newline-terminated) line was written whole by one write(2): if it does not parse,
    // it is not a torn write but a damaged or edited record, reported and never cut away
    EpisodeRecord r;
    try {
      r = parse_record_line(text, src);
    } catch (const InputError& e) {
      if (!last) throw;
      throw InputError(e.source(), e.field(),
                       e.reason() + " (a complete last line that does not parse is not a torn write; the file is left as it is)");
    }
    check_record_belongs(r, job, s.id_, static_cast<std::int64_t>(i), src);
    if (static_cast<std::int64_t>(i) >= job.episodes)
      throw InputError(src, "episode_index", "more records than the job's " + std::to_string(job.episodes) + " episodes");
    records.push_back(std::move(r));
  }
  if (summary) {
    check_records_against_summary(*summary, s.path_, bytes, records);
    if (summary->records_sha256) s.summarized_ = summary->episodes_done;
  }
  // a torn write loses part of one record (a line is a few hundred bytes): a longer unreadable tail
  // is something else, and is reported rather than cut away
  constexpr std::size_t kMaxTornTail = std::size_t{1} << 20;
  if (bytes.size() - keep_bytes > kMaxTornTail)
    throw InputError(s.path_, "", "the " + std::to_string(bytes.size() - keep_bytes) + " bytes after record " +
                                      std::to_string(records.size()) + " are not records and too many for a torn write (repair or remove them)");
  if (keep_bytes < bytes.size()) {
    if (::ftruncate(s.fd_, static_cast<off_t>(keep_bytes)) != 0)
      throw InputError(s.path_, "", "cannot truncate torn last line: " + errno_text());
    s.repaired_bytes_ = static_cast<std::int64_t>(bytes.size() - keep_bytes);
    if (options.log)
      *options.log << "actionshift: " << s.path_ << ": repaired a torn last line (" << s.repaired_bytes_
                   << " bytes removed after record " << records.size() << ")\n";
  }
  s.records_ = std::move(records);
  s.digest_ = std::make_unique<Digest>();
  s.digest_->update(std::string_view(bytes).substr(0, keep_bytes));
  if (s.records_.empty() && bytes.empty()) s.adopt_from_sibling(out_dir, options);
  return s;
}

std::string family_key(const JobSpec& job) {
  nlohmann::json j = job_identity_json(job);
  j.erase("episodes");
  return canonical_dump(j);
}

void ResultStore::adopt_from_sibling(const std::string& out_dir, const StoreOptions& options) {
  namespace fs = std::filesystem;
  const std::string family = family_key(job_);
  std::error_code ec;
  std::vector<EpisodeRecord> best;
  std::string best_id;
  const std::vector<std::string> markers = {'"' + job_.split.sha256 + '"', '"' + job_.backbone.sha256 + '"',
                                            nlohmann::json(job_.method).dump()};
  for (const auto& entry : fs::directory_iterator(out_dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string suffix = ".summary.json";
    if (name.size() != 64 + suffix.size() || !name.ends_with(suffix)) continue;
    const std::string id = name.substr(0, 64);
    if (id == id_ || !is_sha256_hex(id)) continue;
    const fs::path jsonl = fs::path(out_dir) / jsonl_file_name(id);
    try {
      // a sibling has this job's split, backbone and method: a summary whose text lacks one of
      // them is skipped unparsed (a directory of a thousand jobs would otherwise cost every new job
      // a thousand JSON parses)
      const std::string text = detail::read_file(entry.path().string());
      if (!std::all_of(markers.begin(), markers.end(), [&](const std::string& m) { return text.find(m) != std::string::npos; }))
        continue;
      const CheckedSummary summary = parse_job_summary(text, entry.path().string(), id);
      const JobSpec& other = summary.job;
      if (family_key(other) != family || !fs::exists(jsonl)) continue;
      // only records the sibling's summary vouches for (hash and counts) are copied
      const std::string jsonl_bytes = detail::read_file(jsonl.string());
      RecordFile rf = read_record_file(jsonl.string(), /*allow_torn_tail=*/true);
      check_records_against_summary(summary, jsonl.string(), jsonl_bytes, rf.records);
      std::vector<EpisodeRecord> prefix;
      for (auto& r : rf.records) {
        const auto k = static_cast<std::int64_t>(prefix.size());
        if (k >= job_.episodes || r.episode_index != k) break;
        // a record that does not belong to the sibling (edited, or copied from elsewhere) must not
        // become part of this job: the throw skips the sibling, and the job runs its episodes itself
        check_record_belongs(r, other, id, k, jsonl.string());
        prefix.push_back(std::move(r));
      }
      if (prefix.size() > best.size()) {
        best = std::move(prefix);
        best_id = id;
      }
    } catch (const std::exception&) {
      continue;  // not a job summary of ours, or a sibling with bad records: never adopt from it
    }
  }
  if (best.empty()) return;
  for (auto& r : best) {
    r.job_id = id_;
    append(r);
  }
  adopted_ = static_cast<std::int64_t>(best.size());
  adopted_from_ = best_id;
  if (options.log)
    *options.log << "actionshift: job " << id_.substr(0, 12) << ": copied episodes 0.." << adopted_ - 1 << " from job "
                 << best_id.substr(0, 12) << " (the same job with a different episode count)\n";
}

ResultStore::ResultStore(ResultStore&& o) noexcept
    : job_(std::move(o.job_)),
      id_(std::move(o.id_)),
      path_(std::move(o.path_)),
      summary_path_(std::move(o.summary_path_)),
      records_(std::move(o.records_)),
      repaired_bytes_(o.repaired_bytes_),
      adopted_(o.adopted_),
      adopted_from_(std::move(o.adopted_from_)),
      summarized_(o.summarized_),
      digest_(std::move(o.digest_)),
      fsync_(o.fsync_),
      fd_(o.fd_) {
  o.fd_ = -1;
}

ResultStore& ResultStore::operator=(ResultStore&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    job_ = std::move(o.job_);
    id_ = std::move(o.id_);
    path_ = std::move(o.path_);
    summary_path_ = std::move(o.summary_path_);
    records_ = std::move(o.records_);
    repaired_bytes_ = o.repaired_bytes_;
    adopted_ = o.adopted_;
    adopted_from_ = std::move(o.adopted_from_);
    summarized_ = o.summarized_;
    digest_ = std::move(o.digest_);
    fsync_ = o.fsync_;
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

ResultStore::~ResultStore() {
  if (fd_ >= 0) ::close(fd_);  // also releases the flock
}

void ResultStore::append(const EpisodeRecord& record) {
  if (fd_ < 0) throw std::runtime_error("ResultStore::append: store is closed");
  if (complete()) throw std::invalid_argument("ResultStore::append: job already has all its episodes");
  check_record_belongs(record, job_, id_, episodes_done(), "ResultStore::append");
  const std::string line = to_jsonl_line(record) + "\n";
  // one write(2) of the whole line: a kill leaves the line whole or absent (or torn on disk-full,
  // which the next open repairs)
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd_, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(path_ + ": write failed: " + errno_text());
    done += static_cast<std::size_t>(n);
  }
  if (fsync_ && ::fsync(fd_) != 0) throw std::runtime_error(path_ + ": fsync failed: " + errno_text());
  digest_->update(line);
  records_.push_back(record);
}

nlohmann::json make_job_summary(const JobSpec& job, const std::vector<EpisodeRecord>& records,
                                std::int64_t episodes_run, double wall_time_s, const std::string& message,
                                const std::string& records_sha256) {
  if (!is_sha256_hex(records_sha256)) throw std::invalid_argument("make_job_summary: records_sha256 must be 64 lowercase hex digits");
  json s = json::object();
  const auto n = static_cast<std::int64_t>(records.size());
  s["schema_version"] = std::string(kJobSummarySchemaVersion);
  s["records_sha256"] = records_sha256;
  s["job_id"] = job_id(job);
  s["job"] = job_to_json(job);
  s["episodes_requested"] = job.episodes;
  s["episodes_done"] = n;
  s["complete"] = n >= job.episodes;
  s["episodes_run"] = episodes_run;
  s["wall_time_s"] = wall_time_s;
  s["message"] = message;
  s["provenance"] = provenance_to_json(build_provenance());

  std::int64_t once = 0, at_end = 0, flagged = 0, probe_steps = 0, steps = 0;
  double ret = 0.0, disp = 0.0;
  std::map<std::string, std::int64_t> flags;
  struct PerContract {
    std::string sha;
    std::int64_t episodes{0}, successes{0};
  };
  std::map<std::int64_t, PerContract> per_contract;
  for (const auto& r : records) {
    once += r.success_once;
    at_end += r.success_at_end;
    ret += r.task_return;
    steps += r.steps;
    probe_steps += r.probe_steps;
    disp += r.probe_displacement;
    if (!r.safety_flags.empty()) ++flagged;
    for (const auto& f : r.safety_flags) ++flags[f];
    auto& pc = per_contract[r.contract_index];
    pc.sha = r.contract_sha256;
    ++pc.episodes;
    pc.successes += r.success_once;
  }
  auto wilson_json = [&](std::int64_t k) -> json {
    if (n == 0) return nullptr;
    const auto w = wilson_interval(k, n);
    return {{"successes", w.successes}, {"total", w.total}, {"rate", w.rate},
            {"lower", w.lower},         {"upper", w.upper}, {"confidence", w.confidence}};
  };
  auto mean = [&](double total) -> json { return n == 0 ? json(nullptr) : json(total / static_cast<double>(n)); };
  s["success_once"] = wilson_json(once);
  s["success_at_end"] = wilson_json(at_end);
  s["mean_return"] = mean(ret);
  s["mean_steps"] = mean(static_cast<double>(steps));
  s["mean_probe_steps"] = mean(static_cast<double>(probe_steps));
  s["mean_probe_displacement"] = mean(disp);
  s["episodes_with_safety_flags"] = flagged;
  s["safety_flag_counts"] = json::object();
  for (const auto& [name, count] : flags) s["safety_flag_counts"][name] = count;
  s["per_contract"] = json::array();
  for (const auto& [index, pc] : per_contract)
    s["per_contract"].push_back({{"contract_index", index},
                                 {"contract_sha256", pc.sha},
                                 {"episodes", pc.episodes},
                                 {"successes_once", pc.successes},
                                 {"success_once_rate", static_cast<double>(pc.successes) / static_cast<double>(pc.episodes)}});
  return s;
}

void write_json_atomic(const std::string& path, const nlohmann::json& value) {
  write_file_atomic(path, value.dump(2) + "\n");
}

}  // namespace actionshift::eval
