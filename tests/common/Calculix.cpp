#include "brittle/testing/Calculix.h"

#include <cstdio>
#include <cstdlib>

namespace brittle::testing {

std::string ccxNumber(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.13e", v);
  return buffer;
}

double fortranDouble(std::string s) {
  const auto sign = s.find_first_of("+-", 1);
  // (Concatenation rather than insert: GCC 12 flags insert here with a false -Wrestrict.)
  if (sign != std::string::npos && s.find_first_of("Ee") == std::string::npos) s = s.substr(0, sign) + "E" + s.substr(sign);
  return std::stod(s);
}

int runCcx(const std::filesystem::path& dir, const std::string& job) {
  const std::string command =
      "cd '" + dir.string() + "' && CCX_NPROC_EQUATION_SOLVER=1 OMP_NUM_THREADS=1 ccx -i " + job + " > ccx.log 2>&1";
  return std::system(command.c_str());
}

}  // namespace brittle::testing
