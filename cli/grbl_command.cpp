// `hmc grbl`: the sender's link, the grbl front end and the board's session put together, run
// until Ctrl-C or the board is lost.
#include "grbl_command.h"

#include <iostream>

#include "exit_codes.h"
#include "hmc/grbl.h"
#include "hmc/grbl_link.h"
#include "profile_choice.h"

namespace hmc::cli {
void add_grbl_command(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    bool pty = false;
    std::string tcp;
    std::string link;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("grbl", "the board as a grbl 1.1 controller for G-code senders (CNCjs, bCNC, UGS)");
  cmd->add_flag("--pty", o->pty, "serve on a new pseudo-terminal (the default); its name is printed");
  cmd->add_option("--tcp", o->tcp, "serve on a TCP listener instead, HOST:PORT (port 0: any free one)");
  cmd->add_option("--link", o->link, "with --pty: also make this symbolic link to it (e.g. /tmp/ttyGRBL)");
  cmd->footer("Runs until Ctrl-C; every motor stops when the sender goes away. docs/grbl.md");
  cmd->callback([&g, &exit_code, o] {
    if (o->pty && !o->tcp.empty()) {
      std::cerr << "error: --pty and --tcp: choose one\n";
      exit_code = kExitUsage;
      return;
    }
    Result<const Profile*, int> profile = use_profile(g);
    if (!profile) {
      exit_code = profile.error();
      return;
    }
    Result<std::array<std::optional<Axis>, grbl::kAxisCount>> axes = grbl::map_axes(*profile);
    if (!axes) {
      std::cerr << "error: " << axes.error().message << '\n';
      exit_code = kExitInvalid;
      return;
    }
    std::unique_ptr<Session> s = connect(g, exit_code);
    if (!s) return;
    if (s->firmware() != Firmware::kV2) {
      exit_code = report_error(g, SessionError{SessionError::Kind::kTooOld,
                                               "hmc grbl needs the board's events (protocol 2 or later); the board runs "
                                               "the original (seed) firmware: reflash",
                                               proto::Reason::kOk});
      return;
    }
    if (SessionResult<Done> watched = watch_link(*s, g); !watched) {
      exit_code = report_error(g, watched.error());
      return;
    }
    Result<std::unique_ptr<grbl::SenderLink>> link =
        o->tcp.empty() ? grbl::open_pty_sender(o->link) : grbl::open_tcp_sender(o->tcp);
    if (!link) {
      std::cerr << "error: " << link.error().message << '\n';
      exit_code = kExitIo;
      return;
    }
    grbl::SenderLink& sender = **link;
    std::cerr << "hmc grbl: " << (o->tcp.empty() ? "pty " : "listening on ") << sender.address()
              << (o->link.empty() ? "" : " (" + o->link + ")") << std::endl;
    grbl::FrontEnd front(*s, *axes);
    for (;;) {
      if (interrupt_requested()) {
        SessionResult<Done> stopped = front.stop();
        std::cerr << "hmc grbl: interrupted; every motor was sent a stop\n";
        exit_code = stopped ? kExitInterrupted : report_error(g, stopped.error());
        return;
      }
      Result<grbl::SenderLink::Input> in = sender.poll(Millis{2});
      if (!in) {
        std::cerr << "error: " << in.error().message << '\n';
        (void)front.stop();
        exit_code = kExitIo;
        return;
      }
      if (in->connected) {
        std::cerr << "hmc grbl: a sender connected\n";
        front.connected();
      }
      if (!in->bytes.empty()) front.receive(in->bytes);
      SessionResult<Done> served = in->disconnected ? front.sender_gone() : front.service();
      if (in->disconnected) std::cerr << "hmc grbl: the sender went away; every motor was stopped\n";
      if (!served) {
        if (served.error().kind == SessionError::Kind::kInterrupted) continue;  // handled above
        (void)front.stop();
        exit_code = report_error(g, served.error());
        return;
      }
      sender.write(front.take_output());
    }
  });
}

}  // namespace hmc::cli
