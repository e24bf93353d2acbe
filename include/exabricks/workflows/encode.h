// Encoding numbered PNG frames into a movie with ffmpeg (found on PATH, run without a shell): the
// step the command line's movie and the viewer's movie button share.
#pragma once

#include <string>
#include <vector>

namespace exa {

/// The path of an executable program found on PATH, or empty.
std::string findProgram(const std::string& name);

/// Runs a program with arguments (no shell); returns its exit status (-1 when it cannot start).
int runProgram(const std::vector<std::string>& args);

struct MovieEncoding {
  std::string framesDir; ///< holds frame_00000.png onwards (framePath)
  double fps = 24;
  std::string output; ///< .mp4 (H.264) or .webm (VP9)
};

/// The ffmpeg command line a user can run to encode the frames by hand.
std::string encodeCommandExample(const MovieEncoding& e);

/// Encodes the frames into a temporary file next to the output and moves it into place. Returns
/// false when ffmpeg is not installed (nothing written); throws exa::Error when ffmpeg fails or
/// the file cannot be moved.
bool encodeFrames(const MovieEncoding& e);

} // namespace exa
