#include "exabricks/workflows/encode.h"

#include "exabricks/core/error.h"

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace exa {

namespace fs = std::filesystem;

std::string findProgram(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

int runProgram(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

namespace {

std::string framePattern(const MovieEncoding& e) { return (fs::path(e.framesDir) / "frame_%05d.png").string(); }

bool isWebm(const MovieEncoding& e) { return fs::path(e.output).extension() == ".webm"; }

} // namespace

std::string encodeCommandExample(const MovieEncoding& e) {
  return strCat("ffmpeg -framerate ", e.fps, " -i ", framePattern(e),
                isWebm(e) ? " -c:v libvpx-vp9 -b:v 0 -crf 32 " : " -c:v libx264 -pix_fmt yuv420p -crf 18 ", e.output);
}

bool encodeFrames(const MovieEncoding& e) {
  const std::string ffmpeg = findProgram("ffmpeg");
  if (ffmpeg.empty()) return false;
  const std::string ext = fs::path(e.output).extension().string();
  const std::string temporary = strCat(e.output, ".encoding-", ::getpid(), ext);
  std::vector<std::string> args{ffmpeg,        "-y", "-loglevel",     "error", "-framerate",
                                strCat(e.fps), "-i", framePattern(e), "-vf",   "pad=ceil(iw/2)*2:ceil(ih/2)*2"};
  if (isWebm(e))
    args.insert(args.end(), {"-c:v", "libvpx-vp9", "-b:v", "0", "-crf", "32", "-pix_fmt", "yuv420p", "-f", "webm"});
  else
    args.insert(args.end(),
                {"-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18", "-movflags", "+faststart", "-f", "mp4"});
  args.push_back(temporary);
  const int rc = runProgram(args);
  std::error_code ec;
  if (rc != 0) {
    fs::remove(temporary, ec);
    fail(e.output, ": ffmpeg failed (exit status ", rc, "); the frames are in ", e.framesDir,
         "; try: ", encodeCommandExample(e));
  }
  fs::rename(temporary, e.output, ec);
  if (ec) {
    fs::remove(temporary, ec);
    fail(e.output, ": cannot move the encoded movie into place: ", ec.message());
  }
  return true;
}

} // namespace exa
