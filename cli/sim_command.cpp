// `hmc sim`: runs hmc-sim as a child, passes its options on, relays what it prints and adds the
// command to connect once it has said where it listens.
#include "sim_command.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "exit_codes.h"

namespace hmc::cli {
namespace {

volatile pid_t g_child = 0;

void forward_signal(int signal_number) {
  if (g_child > 0) kill(g_child, signal_number);
}

// hmc-sim beside this program (installed together), in the build tree, or on the PATH.
std::string find_simulator() {
  if (const char* env = std::getenv("HMC_SIM_BIN"); env != nullptr && *env != '\0') return env;
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n > 0) {
    std::string dir(self, static_cast<size_t>(n));
    dir = dir.substr(0, dir.rfind('/'));
    for (const std::string& candidate : {dir + "/hmc-sim", dir + "/../firmware/targets/sim/hmc-sim"}) {
      if (access(candidate.c_str(), X_OK) == 0) return candidate;
    }
  }
  return "hmc-sim";
}

// The port name for --port from hmc-sim's announcement, or empty.
std::string port_of(const std::string& line) {
  const std::string tcp = "listening on ";
  if (const size_t at = line.find(tcp); at != std::string::npos && line.find("control") == std::string::npos) {
    return line.substr(at + tcp.size());
  }
  const std::string pty = "hmc-sim: pty ";
  if (line.rfind(pty, 0) == 0) return line.substr(pty.size());
  return {};
}

struct SimArgs {
  std::string tcp;
  bool pty = false;
  std::vector<std::string> extra;
};

int run_simulator(const SimArgs& a) {
  std::vector<std::string> args{find_simulator()};
  if (a.pty) {
    args.push_back("--pty");
  } else {
    args.insert(args.end(), {"--tcp", a.tcp.empty() ? "127.0.0.1:4000" : a.tcp});
  }
  args.insert(args.end(), a.extra.begin(), a.extra.end());
  int err[2];
  if (pipe(err) != 0) {
    std::cerr << "error: cannot start the simulator: " << std::strerror(errno) << '\n';
    return kExitIo;
  }
  const pid_t child = fork();
  if (child < 0) {
    std::cerr << "error: cannot start the simulator: " << std::strerror(errno) << '\n';
    return kExitIo;
  }
  if (child == 0) {
    dup2(err[1], STDERR_FILENO);
    close(err[0]);
    close(err[1]);
    std::vector<char*> argv;
    for (std::string& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    std::fprintf(stderr, "hmc-sim: cannot run %s: %s\n", argv[0], std::strerror(errno));
    _exit(kExitIo);
  }
  close(err[1]);
  // Ctrl-C reaches the child too (same process group); a signal sent to this process alone
  // (kill, a service manager, timeout) is passed on, so stopping `hmc sim` stops the board.
  g_child = child;
  struct sigaction pass_on {};
  pass_on.sa_handler = forward_signal;
  pass_on.sa_flags = SA_RESTART;  // keep relaying what the simulator prints as it stops
  sigemptyset(&pass_on.sa_mask);
  sigaction(SIGINT, &pass_on, nullptr);
  sigaction(SIGTERM, &pass_on, nullptr);
  std::unique_ptr<FILE, int (*)(FILE*)> in(fdopen(err[0], "r"), fclose);
  char buffer[1024];
  while (in && std::fgets(buffer, sizeof buffer, in.get()) != nullptr) {
    std::string line(buffer);
    std::cerr << line << std::flush;
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    if (const std::string port = port_of(line); !port.empty()) {
      std::cerr << "hmc: the simulated board is up; in another terminal:\n"
                << "  hmc --port " << port << " status\n"
                << "  export HMC_PORT=" << port << "   # then plain `hmc move 1 3200 --wait`\n"
                << "Ctrl-C here stops it.\n"
                << std::flush;
    }
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) && (WTERMSIG(status) == SIGINT || WTERMSIG(status) == SIGTERM) ? kExitOk : kExitIo;
}

}  // namespace

void add_sim_command(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<SimArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sim", "run the simulated board on TCP (default 127.0.0.1:4000) or a pseudo-terminal, and say how to connect");
  cmd->add_option("--tcp", a->tcp, "HOST:PORT to listen on (port 0: any free one)");
  cmd->add_flag("--pty", a->pty, "serve a pseudo-terminal instead of TCP");
  cmd->add_option("simulator-options", a->extra,
                  "further hmc-sim options after --, e.g. -- --seed --trace t.jsonl (docs/sim.md)");
  cmd->callback([&exit_code, a] { exit_code = run_simulator(*a); });
}

}  // namespace hmc::cli
