// Content ids: SHA-256 through OpenSSL's EVP interface.
#include "chasles/server/content_hash.h"

#include <openssl/evp.h>

#include <stdexcept>

namespace chasles {

std::string Sha256Hex(std::string_view bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("OpenSSL EVP_Digest(SHA-256) failed");
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex(2 * length, '0');
  for (unsigned int i = 0; i < length; ++i) {
    hex[2 * i] = kHex[digest[i] >> 4];
    hex[2 * i + 1] = kHex[digest[i] & 0xf];
  }
  return hex;
}

std::string ContentId(std::string_view bytes) { return Sha256Hex(bytes).substr(0, 32); }

}  // namespace chasles
