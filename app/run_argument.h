#pragma once
// The RUN argument every command that reads a run takes, checked before the
// command starts: a path that does not exist is "no such folder" (not "holds
// no bosfuse run", which is for a folder that exists and holds none), and a
// file inside a run folder (`RUN/run.sqlite`, tab-completed by a shell) is
// understood as its run. Use it on every positional run folder, so the
// commands agree on what a run argument may be.

#include <string>

namespace CLI {
class Validator;
}

namespace bosfuse::app {

// Rewrites `path` to its run folder when it names a file inside one, and
// returns an error message ("" when the argument is usable). A folder that
// exists is left for the store to judge.
std::string resolve_run_argument(std::string& path);

// resolve_run_argument as a CLI11 transform: a bad run argument is a usage
// error (CLI::ValidationError, exit 105) naming the path.
CLI::Validator run_folder_argument();

}  // namespace bosfuse::app
