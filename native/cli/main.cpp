// `lantern`: the command-line front end of the core.
#include <cstdio>
#include <cstring>

#include "lantern/lantern.h"

static int usage() {
  std::fprintf(stderr, "usage: lantern --version\n");
  return 2;
}

int main(int argc, char** argv) {
  if (argc >= 2 && (!std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version"))) {
    std::printf("lantern %s (ABI %d)\n", lt_version(), lt_abi_version());
    return 0;
  }
  return usage();
}
