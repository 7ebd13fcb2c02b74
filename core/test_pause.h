// A test hook that widens a race window: at a named point, the process
// sleeps when the environment variable DOASIDO_TEST_PAUSE names that point
// ("point=milliseconds[,point=milliseconds...]"), so a test can act while
// a merge places its folders or a version copies its episodes. Without the
// variable it does nothing (one getenv per call).
#pragma once

#include <string_view>

namespace doasido {

inline constexpr const char* kTestPauseVariable = "DOASIDO_TEST_PAUSE";

// The points in use, each named where it pauses.
inline constexpr const char* kPauseMergePlacement = "merge_placement";  // before each folder move
inline constexpr const char* kPauseVersionEpisode = "version_episode";  // after each episode copied

void TestPause(std::string_view point);

}  // namespace doasido
