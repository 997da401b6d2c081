// Writes the seed pack (PackSupport.h) to the path given, for the pack targets' seed corpus:
//   brittle_fuzz_seed_pack tests/fuzz/corpus/fuzz_pack_bytes/seed.pack.h5
#include <cstdio>

#include "PackSupport.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output.h5>\n", argv[0]);
    return 2;
  }
  const brittle::Status written = brittle::writePack(brittle::fuzz::makeSeedPack(), argv[1]);
  if (!written.ok()) {
    std::fprintf(stderr, "%s\n", written.error().message.c_str());
    return 1;
  }
  return 0;
}
