#include "tests/deploy/slurm_cluster.h"

#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <thread>

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

std::string ShortHostname() {
  char name[256] = {};
  gethostname(name, sizeof(name) - 1);
  const std::string host = name;
  return host.substr(0, host.find('.'));
}

std::string LastLine(const std::string& text) {
  const auto end = text.find_last_not_of('\n');
  if (end == std::string::npos) return "(no output)";
  const auto begin = text.rfind('\n', end);
  return text.substr(begin == std::string::npos ? 0 : begin + 1,
                     end - (begin == std::string::npos ? 0 : begin + 1) + 1);
}

}  // namespace

SlurmCluster::SlurmCluster(const fs::path& dir) : dir_(dir) {
  if (geteuid() != 0) {
    why_not_ = "Slurm's daemons must start as root and this test runs as uid " + std::to_string(geteuid());
    return;
  }
  for (const char* binary : {"/usr/sbin/munged", "/usr/sbin/slurmctld", "/usr/sbin/slurmd", "/usr/bin/sbatch",
                             "/usr/sbin/mungekey"}) {
    if (!fs::exists(binary)) {
      why_not_ = std::string(binary) + " is not installed (scripts/install-deps installs munge and Slurm)";
      return;
    }
  }
  Start();
}

void SlurmCluster::Start() {
  const auto conf = dir_ / "slurm.conf";
  setenv("SLURM_CONF", conf.c_str(), 1);
  fs::create_directories(dir_ / "state");
  fs::create_directories(dir_ / "spool");
  fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                            fs::perms::others_read | fs::perms::others_exec);
  const auto key = dir_ / "munge.key";
  if (Process({"/usr/sbin/mungekey", "--create", "--keyfile=" + key.string(), "--bits=1024"},
              dir_ / "mungekey.log")
          .Wait() != 0) {
    why_not_ = "mungekey failed: " + LastLine(ReadBytes(dir_ / "mungekey.log"));
    return;
  }
  const auto socket = dir_ / "munge.socket";
  // --force: munged refuses a socket folder others can traverse, which slurmd's job steps need.
  munged_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/sbin/munged", "--foreground", "--force", "--socket=" + socket.string(),
                               "--key-file=" + key.string(), "--pid-file=" + (dir_ / "munged.pid").string(),
                               "--seed-file=" + (dir_ / "munged.seed").string(),
                               "--log-file=" + (dir_ / "munged.log").string()},
      dir_ / "munged.out");
  if (!WaitUntil([&] { return fs::exists(socket); }, std::chrono::seconds(10))) {
    why_not_ = "munged did not start: " + LastLine(ReadBytes(dir_ / "munged.out"));
    return;
  }
  const std::string host = ShortHostname();
  std::ofstream(conf)
      << "ClusterName=endorecontest\n"
      << "SlurmctldHost=" << host << "(127.0.0.1)\n"
      << "SlurmctldPort=" << FreePort() << "\nSlurmdPort=" << FreePort() << "\n"
      << "AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket=" << socket.string() << "\n"
      << "SlurmUser=root\nSlurmdUser=root\n"
      << "StateSaveLocation=" << (dir_ / "state").string() << "\n"
      << "SlurmdSpoolDir=" << (dir_ / "spool").string() << "\n"
      << "SlurmctldPidFile=" << (dir_ / "slurmctld.pid").string() << "\n"
      << "SlurmdPidFile=" << (dir_ / "slurmd.pid").string() << "\n"
      << "SlurmctldLogFile=" << (dir_ / "slurmctld.log").string() << "\n"
      << "SlurmdLogFile=" << (dir_ / "slurmd.log").string()
      << "\n"
      // No cgroups in a container: plain process tracking, no task binding, no accounting.
      << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n"
      << "JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n"
      << "SwitchType=switch/none\nMpiDefault=none\n"
      << "SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\n"
      << "SchedulerType=sched/builtin\nReturnToService=2\nKillWait=5\n"
      << "NodeName=" << host
      << " NodeAddr=127.0.0.1 CPUs=" << std::max(1u, std::thread::hardware_concurrency())
      << " RealMemory=2000 State=UNKNOWN\n"
      << "PartitionName=test Nodes=" << host << " Default=YES MaxTime=INFINITE State=UP\n";
  slurmctld_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/sbin/slurmctld", "-D", "-i", "-f", conf.string()},
      dir_ / "slurmctld.out");
  slurmd_ = std::make_unique<Process>(std::vector<std::string>{"/usr/sbin/slurmd", "-D", "-f", conf.string()},
                                      dir_ / "slurmd.out");
  const bool idle = WaitUntil(
      [&] {
        return Command({"/usr/bin/sinfo", "-h", "-o", "%t"}).out.find("idle") != std::string::npos;
      },
      std::chrono::seconds(30));
  if (!idle) why_not_ = "the Slurm node did not become idle within 30 s: " + LogTail();
}

std::string SlurmCluster::LogTail() const {
  return "slurmctld: " + LastLine(ReadBytes(dir_ / "slurmctld.out")) +
         "; slurmd: " + LastLine(ReadBytes(dir_ / "slurmd.out"));
}

CliResult SlurmCluster::Command(const std::vector<std::string>& argv) const {
  TempDir scratch("slurm-command");
  CliResult result;
  result.exit_code = Process(argv, scratch / "out", scratch / "err").Wait();
  result.out = ReadBytes(scratch / "out");
  result.err = ReadBytes(scratch / "err");
  return result;
}

void SlurmCluster::CancelAll() {
  if (!slurmctld_) return;
  Command({"/usr/bin/scancel", "--full", "--signal=TERM", "--user=root"});
  const bool gone = WaitUntil(
      [&] {
        return Command({"/usr/bin/squeue", "-h"}).out.empty();
      },
      std::chrono::seconds(30));
  if (!gone) Command({"/usr/bin/scancel", "--user=root"});
}

SlurmCluster::~SlurmCluster() {
  CancelAll();
  for (auto* daemon : {slurmd_.get(), slurmctld_.get(), munged_.get()}) {
    if (!daemon) continue;
    daemon->Signal(SIGTERM);
    daemon->Wait();
  }
  unsetenv("SLURM_CONF");
}

}  // namespace endorecon::testing
