#pragma once
/// \file
/// Content hashes used as robot and scene ids (SHA-256 via OpenSSL).

#include <string>
#include <string_view>

namespace chasles {

/// SHA-256 of `bytes` as 64 lowercase hex digits.
std::string Sha256Hex(std::string_view bytes);

/// The id of a piece of content: the first 128 bits of its SHA-256, 32 hex digits.
std::string ContentId(std::string_view bytes);

}  // namespace chasles
