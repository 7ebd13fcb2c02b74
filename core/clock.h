// The clock of every timestamp the database keeps (runs, reviews,
// downloads): seconds since the epoch. In core because the download sidecar
// (ingest/download.h) stamps its files with it without a database.
#pragma once

namespace doasido {

// Seconds since the epoch (CLOCK_REALTIME).
double Now();

// CPU milliseconds this thread has used (CLOCK_THREAD_CPUTIME_ID): what a
// model run costs, whatever else the machine runs.
double ThreadCpuMs();

}  // namespace doasido
