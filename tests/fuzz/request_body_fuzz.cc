// The review API's request bodies (review/request_body.h: size and depth
// limits, whole ids in range) and the JSON limits under them
// (core/json_input.h), on arbitrary bytes. Only doasido::Error may come
// out; an id that is returned must be in [1, kMaxId].
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "review/request_body.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string body(reinterpret_cast<const char*>(data), size);
  try {
    const doasido::Json j = doasido::review::ParseRequestBody(body);
    for (const char* key : {"clip_id", "trial_id"}) {
      try {
        const std::int64_t id = doasido::review::RequireId(j, key);
        if (id < 1 || id > doasido::review::kMaxId) std::abort();
      } catch (const doasido::Error&) {
      }
    }
    (void)j.value("stage", std::string());
  } catch (const doasido::Error&) {
  } catch (const doasido::Json::type_error&) {
    // j.value on a key of another type: the server answers it as bad JSON.
  }
  try {
    (void)doasido::review::PathId(body);
  } catch (const doasido::Error&) {
  }
  return 0;
}
