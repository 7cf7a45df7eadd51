// Checks of numeric command-line values for every command of the product, with messages that say
// the bound in words (CLI11's own NonNegativeNumber and PositiveNumber print the largest double,
// three hundred digits, as their upper bound).
#pragma once

#include <CLI/CLI.hpp>

namespace endorecon {

// A finite number >= 0: "--fps: -1 is negative; expected a number >= 0".
CLI::Validator AtLeastZero();

// A finite number > 0: "--limit: 0 is not above 0".
CLI::Validator AboveZero();

// A finite number in [low, high]: "--fps: 2000: expected 0.01 to 1000". CLI11's Range lets NaN
// through (no comparison with it is true): `to-dicom --fps nan` wrote a file (found 2026-12-06).
CLI::Validator Within(double low, double high);

// The held-out frames' spacing: 0 (none held out) or K >= 2 (every K-th frame); 1 would hold every
// frame out of training.
CLI::Validator HoldoutSpacing();

// A time budget in seconds: 0 (none) or at least kLeastTimeBudgetS (common/job_bounds.h).
CLI::Validator TimeBudget();

// An address to listen on: HOST:PORT or [IPv6]:PORT with a port of 0-65535 (0 picks one), or
// unix:PATH. gRPC took 127.0.0.1:99999 and listened on a port of its choosing.
CLI::Validator ListenAddress();

// A server's address to call: as ListenAddress, with a port of 1-65535. gRPC took 127.0.0.1:99999
// modulo 65536 and "localhost" as port 443.
CLI::Validator ServerAddress();

// A DICOM storage SCP's address: HOST:PORT or [IPv6]:PORT with a port of 1-65535, the port a PACS
// is told to send to (0 would pick one no PACS knows); no unix:PATH.
CLI::Validator StorageScpAddress();

// Makes every integer option of `app` and of its commands read decimal numbers only: CLI11 reads
// them as C does, so `--skip-left 011` skipped 9 frames without a word (found 2026-12-07). Leading
// zeros are dropped; anything but an optional sign and digits (0x9, 9.0, 9abc) is refused as no
// whole number. Call once every option is added.
void DecimalIntegers(CLI::App& app);

}  // namespace endorecon
