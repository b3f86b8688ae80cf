// `mpirun -n N bosfuse process` (cluster/frame_farm.h) against a processing
// in one process of the same run: the same stored numbers; and a rank
// killed in the middle of a job. Open MPI's own mpirun on loopback, as root
// in CI (its two confirming variables), oversubscribed on two cores.

#ifdef BOSFUSE_HAVE_MPI

#include <signal.h>

#include <fstream>
#include <regex>

#include "app/process_test_run.h"

namespace bosfuse {
namespace {

using namespace process_testing;

std::string mpirun(int ranks) { return "mpirun --oversubscribe -n " + std::to_string(ranks) + " "; }

// Frames each rank evaluated, from the report's "rank R on HOST: N frames" lines.
std::map<int, int> frames_by_rank(const std::string& output) {
  std::map<int, int> out;
  const std::regex line(R"(rank (\d+) on \S+: (\d+) frames)");
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    out[std::stoi((*it)[1])] = std::stoi((*it)[2]);
  }
  return out;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The process mpirun started as `rank` (its child with that rank in its environment).
pid_t rank_pid(pid_t mpirun_pid, int rank) {
  const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = read_file(entry.path() / "stat");
    const auto after_name = stat.rfind(')');
    if (after_name == std::string::npos) continue;
    std::istringstream fields(stat.substr(after_name + 2));
    char state = 0;
    pid_t parent = 0;
    fields >> state >> parent;
    if (parent != mpirun_pid) continue;
    std::string env = read_file(entry.path() / "environ");
    std::replace(env.begin(), env.end(), '\0', '\n');
    if (("\n" + env).find("\n" + wanted + "\n") != std::string::npos) return std::stoi(name);
  }
  return -1;
}

class ProcessMpi : public ProcessCli {
 protected:
  // Forty frames: enough for every rank to get some, and for a job to be
  // caught in the middle.
  void SetUp() override {
    make_run(true, 40);
    // What Open MPI asks of a root user (CI runs as root); mpirun inherits them.
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  }

  std::filesystem::path copy_of_run(const std::string& name) {
    const auto to = dir_.path() / name;
    std::filesystem::copy(run_dir(), to, std::filesystem::copy_options::recursive);
    return to;
  }
};

TEST_F(ProcessMpi, ThreeRanksStoreWhatOneProcessStores) {
  const auto alone = copy_of_run("alone");
  const std::string options = " --mode full " + grid_;
  const auto single = testing::run_command(kBosfuse + " process " + alone.string() + options, 300);
  ASSERT_EQ(single.exit_code, 0) << single.output;

  const auto job = testing::run_command(mpirun(3) + kBosfuse + " process " + run_dir().string() + options, 300);
  ASSERT_EQ(job.exit_code, 0) << job.output;
  const auto ranks = frames_by_rank(job.output);
  ASSERT_EQ(ranks.size(), 3u) << job.output;
  int frames = 0, ranks_with_frames = 0;
  for (const auto& [rank, n] : ranks) frames += n, ranks_with_frames += n > 0;
  EXPECT_EQ(frames, 40) << job.output;
  EXPECT_GE(ranks_with_frames, 2) << "the frames were not spread: " << job.output;

  const StoredResults distributed(run_dir()), one(alone);
  EXPECT_EQ(distributed.fields.size(), 80u) << "displacement and temperature files of every frame";
  EXPECT_TRUE(distributed == one) << "a distributed processing stored other numbers than one process";
  // The quality index (rank 0 reads the last frame itself) matches too.
  const storage::ProcessingStore a(run_dir()), b(alone);
  EXPECT_EQ(nlohmann::json::parse(a.current_processing()->summary_json).at("quality"),
            nlohmann::json::parse(b.current_processing()->summary_json).at("quality"));
}

TEST_F(ProcessMpi, AKilledRankFailsTheJobLeavesThePreviousResultsAndResumeCompletesIt) {
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const StoredResults previous(run_dir());
  const auto uninterrupted = copy_of_run("uninterrupted");

  std::vector<std::string> argv{"mpirun", "--oversubscribe", "-n", "3", kBosfuse, "process", run_dir().string()};
  argv.insert(argv.end(), kSlowOptions.begin(), kSlowOptions.end());
  testing::BackgroundProcess job(argv);
  ASSERT_TRUE(testing::wait_for([&] { return staged_frames(run_dir()) >= 2; }, std::chrono::seconds(120)));
  const pid_t victim = rank_pid(job.pid(), 2);
  ASSERT_GT(victim, 0) << "rank 2 not found among mpirun's children";
  ASSERT_EQ(kill(victim, SIGKILL), 0);
  const int status = job.wait_exit(std::chrono::seconds(60));
  EXPECT_NE(status, 0) << "the job must fail when one of its ranks dies";
  EXPECT_NE(status, -1) << "mpirun did not end within a minute of the rank's death";
  ASSERT_LT(staged_frames(run_dir()), 40) << "it finished before a rank could be killed";
  EXPECT_TRUE(StoredResults(run_dir()) == previous) << "the previous results changed";

  const auto resumed = testing::run_command(mpirun(2) + kBosfuse + " process --resume " + run_dir().string(), 300);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("done before the resume"), std::string::npos) << resumed.output;
  std::string options;
  for (const auto& o : kSlowOptions) options += " " + o;
  ASSERT_EQ(testing::run_command(kBosfuse + " process " + uninterrupted.string() + options, 300).exit_code, 0);
  EXPECT_TRUE(StoredResults(run_dir()) == StoredResults(uninterrupted))
      << "a resumed processing differs from an uninterrupted one";
}

// examples/slurm/process.sbatch as sbatch would run it on one node: Slurm's
// variables set as a two-task, one-CPU-per-task job would have them, Open
// MPI's mpirun standing in for srun (no Slurm here).
TEST_F(ProcessMpi, TheSlurmRecipeRunsTheJobOnItsRanksAndThreads) {
  const std::string script = std::string(BOSFUSE_SOURCE_DIR) + "/examples/slurm/process.sbatch";
  const std::string env =
      "SLURM_JOB_ID=4242 SLURM_JOB_NUM_NODES=1 SLURM_NTASKS=2 SLURM_CPUS_PER_TASK=1 BOSFUSE=" + kBosfuse +
      " BOSFUSE_LAUNCHER='mpirun --oversubscribe -n 2' ";
  const auto job = testing::run_command("env " + env + "bash " + script + " " + run_dir().string() + " " + grid_, 300);
  ASSERT_EQ(job.exit_code, 0) << job.output;
  EXPECT_NE(job.output.find("job 4242 on 1 nodes, 2 ranks x 1 threads"), std::string::npos) << job.output;
  EXPECT_NE(job.output.find("distributed over 2 MPI ranks"), std::string::npos) << job.output;
  EXPECT_NE(job.output.find("bosfuse-process: done"), std::string::npos) << job.output;
  EXPECT_EQ(StoredResults(run_dir()).samples.at(0).size(), 40u);

  const auto usage = testing::run_command("bash " + script);
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_NE(usage.output.find("usage: sbatch"), std::string::npos) << usage.output;
  const auto failed =
      testing::run_command("env " + env + "bash " + script + " " + run_dir().string() + " --resume", 120);
  EXPECT_NE(failed.exit_code, 0) << "nothing to resume: " << failed.output;
  EXPECT_NE(failed.output.find("nothing to resume"), std::string::npos) << failed.output;
  EXPECT_NE(failed.output.find("earlier results are intact"), std::string::npos) << failed.output;
}

}  // namespace
}  // namespace bosfuse

#endif  // BOSFUSE_HAVE_MPI
