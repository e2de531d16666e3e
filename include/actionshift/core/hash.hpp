#pragma once
/// \file SHA-256 through OpenSSL's EVP interface (lowercase hex), as the reference's `sha256_hex`.

#include <openssl/evp.h>

#include <array>
#include <stdexcept>
#include <string>
#include <string_view>

namespace actionshift {

/// Raw 32-byte SHA-256 digest of `bytes`.
inline std::array<unsigned char, 32> sha256_bytes(std::string_view bytes) {
  std::array<unsigned char, 32> digest{};
  unsigned int len = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest.data(), &len, EVP_sha256(), nullptr) != 1 || len != 32)
    throw std::runtime_error("sha256: OpenSSL EVP_Digest failed");
  return digest;
}

/// Lowercase 64-character hex SHA-256 of `bytes` (UTF-8 text is hashed as its bytes).
inline std::string sha256_hex(std::string_view bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  const auto d = sha256_bytes(bytes);
  std::string out(64, '0');
  for (std::size_t i = 0; i < d.size(); ++i) {
    out[2 * i] = kHex[d[i] >> 4];
    out[2 * i + 1] = kHex[d[i] & 0xF];
  }
  return out;
}

/// True if `s` looks like a lowercase hex SHA-256 (64 characters of [0-9a-f]).
inline bool is_sha256_hex(std::string_view s) {
  if (s.size() != 64) return false;
  for (char c : s)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

}  // namespace actionshift
