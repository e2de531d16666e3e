#pragma once
/// \file
/// The container shared by ActionShift's binary weight files (`.asmlp` backbones, `.asid`
/// identifiers): 8 magic bytes | u32 format version | u32 header length | JSON header | payload
/// (little-endian float32s, whose SHA-256 the header records as `payload_sha256`). Reading checks
/// the frame and returns the header and the payload; what the payload holds is the caller's.

#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"

#include <nlohmann/json.hpp>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <string_view>

namespace actionshift::weight_file {

static_assert(std::endian::native == std::endian::little, "weight files are read on little-endian hosts");

/// Largest header accepted (the shipped headers are a few hundred bytes).
inline constexpr std::uint32_t kMaxHeaderBytes = 1u << 20;

namespace detail {
inline void put_u32(std::string& out, std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); }
inline std::uint32_t get_u32(std::string_view s, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}
}  // namespace detail

/// The file's bytes: magic (exactly 8 bytes), version, the header (dumped compactly) and the payload.
inline std::string frame(std::string_view magic, std::uint32_t version, const nlohmann::json& header, std::string_view payload) {
  const std::string h = header.dump();
  std::string out(magic.substr(0, 8));
  detail::put_u32(out, version);
  detail::put_u32(out, static_cast<std::uint32_t>(h.size()));
  out += h;
  out += payload;
  return out;
}

struct Unframed {
  nlohmann::json header;    ///< a JSON object
  std::string_view payload;  ///< the bytes after the header (a view into the input)
};

/// Checks the frame of `bytes` read from `source`: size, magic, version and a header that is a JSON
/// object. `what` names the file kind in messages ("MLP weight file"). Throws InputError(source,
/// field, reason) naming `magic`, `version` or `header`.
inline Unframed unframe(std::string_view bytes, std::string_view magic, std::uint32_t version, const std::string& source,
                        const std::string& what) {
  if (bytes.size() < 16)
    throw InputError(source, "", "not an ActionShift " + what + " (truncated: " + std::to_string(bytes.size()) + " bytes)");
  if (std::memcmp(bytes.data(), magic.data(), 8) != 0) throw InputError(source, "magic", "not an ActionShift " + what + " (bad magic)");
  const std::uint32_t v = detail::get_u32(bytes, 8);
  if (v != version)
    throw InputError(source, "version", "unsupported format version " + std::to_string(v) + " (expected " + std::to_string(version) + ")");
  const std::uint32_t hlen = detail::get_u32(bytes, 12);
  if (hlen > kMaxHeaderBytes || 16 + static_cast<std::size_t>(hlen) > bytes.size())
    throw InputError(source, "header", "truncated file: header of " + std::to_string(hlen) + " bytes does not fit");
  Unframed u{parse_json_input(bytes.substr(16, hlen), source, "header"), bytes.substr(16 + hlen)};
  if (!u.header.is_object()) throw InputError(source, "header", "header is not a JSON object");
  return u;
}

/// Throws InputError(source, "payload", …) unless the payload is exactly `floats` float32s and its
/// SHA-256 is the header's `payload_sha256` (which must be present when `checksum_required`; files
/// written before the field existed have none). `size_note` is appended to a size mismatch's reason.
inline void check_payload(const Unframed& u, std::int64_t floats, const std::string& source, bool checksum_required,
                          const std::string& size_note = "") {
  const auto size = static_cast<std::int64_t>(u.payload.size());
  if (size != floats * 4)
    throw InputError(source, "payload", (size < floats * 4 ? "truncated: " : "trailing bytes: ") + std::to_string(size) +
                                            " bytes, expected " + std::to_string(floats * 4) + size_note);
  const auto it = u.header.find("payload_sha256");
  if (it == u.header.end() ? checksum_required : (!it->is_string() || *it != sha256_hex(u.payload)))
    throw InputError(source, "payload", "checksum mismatch (corrupt file)");
}

/// The whole file at `path` (at most `max_bytes`); InputError(path, "", …) for a directory, an
/// oversized or unreadable file.
inline std::string read(const std::string& path, std::uintmax_t max_bytes, const std::string& what) {
  return read_input_file(path, what, max_bytes);
}

}  // namespace actionshift::weight_file
