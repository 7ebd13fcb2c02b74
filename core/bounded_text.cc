#include "core/bounded_text.h"

namespace doasido {

std::string BoundedTail(std::string_view text, std::size_t max_bytes,
                        const std::string& full_text_at) {
  if (text.size() <= max_bytes) return std::string(text);
  std::string marker = "[" + std::to_string(text.size()) + " bytes; ";
  marker += full_text_at.empty() ? std::string("the last ones follow]\n")
                                 : "the whole text is in " + full_text_at + "; its end follows]\n";
  if (marker.size() >= max_bytes) return marker.substr(0, max_bytes);
  std::size_t start = text.size() - (max_bytes - marker.size());
  // Continuation bytes (10xxxxxx) belong to the character before them.
  while (start < text.size() && (static_cast<unsigned char>(text[start]) & 0xC0) == 0x80) ++start;
  return marker + std::string(text.substr(start));
}

}  // namespace doasido
