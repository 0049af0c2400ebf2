#pragma once
// What a command removes when SIGINT or SIGTERM ends it before it finished: the output folder it
// created (still empty, or partial: its outputs are written last) and its own reference cache lock
// file. Without this, a killed `run` or `reference` left an empty output folder and a stale
// `<entry>.exr.lock` behind. The paths are registered while they are this process's to remove;
// the command that wants the cleanup (app/: cleanUpOnSignal) waits for the signal on a thread of
// its own, so the removal runs as ordinary code, not inside a signal handler.
#include <string>

namespace shadowlab {

// A file or folder (removed with everything under it) to remove if the process is interrupted.
void registerInterruptPath(const std::string& path);
// No longer to remove (the command kept it, or removed it itself).
void unregisterInterruptPath(const std::string& path);
// Removes every registered path (best effort, no throw); returns how many were removed.
int removeInterruptPaths();

}  // namespace shadowlab
