#pragma once
// run and reference: SIGINT or SIGTERM ends the command with exit 128 + the signal's number after
// removing what it created and has not finished (the registered paths of
// shadowlab/compare/interrupt_cleanup.h: its new output folder, its reference cache lock). The
// long commands (sweep, tune) keep their own handlers (installStopHandlers in command.h).
#include <string>

namespace shadowlab::app {

// Blocks SIGINT and SIGTERM in the calling thread, and so in every thread started after it (TBB's,
// Embree's, the Vulkan driver's), and waits for them on a thread of its own, which does the
// removal as ordinary code rather than in a signal handler. Call it first, before any thread starts.
void cleanUpOnSignal(const std::string& command);

// The outermost folder of `dir` that does not exist yet, "" when `dir` exists: the folder an
// OutputFolder for `dir` is about to create, and so this command's to remove if interrupted.
std::string firstMissingFolder(const std::string& dir);

}  // namespace shadowlab::app
