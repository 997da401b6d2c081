// Calculix.h — what the suites that check brittle against CalculiX (ccx, Debian's calculix-ccx)
// share: numbers as ccx reads and writes them, and running ccx on a deck.
#pragma once

#include <filesystem>
#include <string>

namespace brittle::testing {

/// A deck field: 14 significant digits in at most 20 characters, the most ccx reads per field.
std::string ccxNumber(double v);

/// A Fortran E-format field as ccx writes it; ccx drops the "E" of three-digit exponents
/// ("1.234567-100").
double fortranDouble(std::string s);

/// Runs `ccx -i <job>` in dir on one thread (the machine is shared), its output to dir/ccx.log.
/// Returns the shell's status: 0 on success.
int runCcx(const std::filesystem::path& dir, const std::string& job);

}  // namespace brittle::testing
