// `lantern`: the command-line front end of the core.
//   lantern --version
//   lantern merge OUT.exr PART.exr...        sample-split parts into one render (lt_merge_exr)
//   lantern farm submit|status|wait ...      farm renders (lantern_farm.py, installed beside this binary)
#include <unistd.h>

#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "lantern/lantern.h"

static int usage() {
  std::fprintf(stderr,
               "usage: lantern --version\n"
               "       lantern merge OUT.exr PART.exr [PART.exr...]\n"
               "       lantern farm submit|status|wait ... (lantern farm --help)\n");
  return 2;
}

static std::string self_dir() {
  char buf[PATH_MAX];
  ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return ".";
  std::string p(buf, size_t(n));
  return p.substr(0, p.find_last_of('/'));
}

static int merge(int argc, char** argv) {
  if (argc < 4) return usage();
  std::vector<const char*> parts(argv + 3, argv + argc);
  if (lt_merge_exr(argv[2], parts.data(), int(parts.size())) != LT_OK) {
    std::fprintf(stderr, "lantern merge: %s\n", lt_last_error());
    return 1;
  }
  std::printf("lantern merge: merged %d parts into %s\n", int(parts.size()), argv[2]);
  return 0;
}

// The farm front end is a stdlib-only Python script beside the binary; it calls back into this
// binary (LANTERN_CLI) for the merge job.
static int farm(int argc, char** argv) {
  const std::string dir = self_dir(), script = dir + "/lantern_farm.py";
  if (access(script.c_str(), R_OK) != 0) {
    std::fprintf(stderr, "lantern farm: %s is missing (it is installed beside the lantern binary)\n", script.c_str());
    return 1;
  }
  setenv("LANTERN_CLI", (dir + "/lantern").c_str(), 1);
  // The user's PATH, for the jobs: a python3 launcher (pyenv's shim) may put its own bin first,
  // and Blender's embedded Python then takes that interpreter's prefix and misses its modules.
  if (const char* path = std::getenv("PATH")) setenv("LANTERN_FARM_PATH", path, 1);
  std::vector<char*> args = {const_cast<char*>("python3"), const_cast<char*>(script.c_str())};
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  const char* python = std::getenv("LANTERN_PYTHON");
  execvp(python && *python ? python : "python3", args.data());
  std::fprintf(stderr, "lantern farm: could not run python3: %s\n", std::strerror(errno));
  return 1;
}

int main(int argc, char** argv) {
  if (argc >= 2 && (!std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version"))) {
    std::printf("lantern %s (ABI %d)\n", lt_version(), lt_abi_version());
    return 0;
  }
  if (argc >= 2 && !std::strcmp(argv[1], "merge")) return merge(argc, argv);
  if (argc >= 2 && !std::strcmp(argv[1], "farm")) return farm(argc, argv);
  return usage();
}
