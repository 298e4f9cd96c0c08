// `hmc completion bash|zsh`: walks the CLI11 app (CLI11 2.1 has no completion generator) into one
// table per command path — its subcommands, its options and which options take a value — and
// writes that table as a bash or zsh function. Both scripts follow the same rule: words that name
// a subcommand of the path so far descend into it, an option that takes a value skips its value,
// and the word under the cursor is completed from the subcommands (or, after '-', the options of
// the path and of hmc itself, which may follow any subcommand); where neither applies, file names.
#include "completion_command.h"

#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "exit_codes.h"

namespace hmc::cli {
namespace {

struct Entry {
  std::string name;
  std::string description;
};

// One command path ("" is hmc itself, then "frame", "frame encode", ...).
struct Node {
  std::string path;
  std::vector<Entry> children;
  std::vector<Entry> options;
  std::vector<std::string> valued;  // options that take a value
};

// CLI11 hides options and subcommands whose group is empty.
void walk(const CLI::App& app, const std::string& path, std::vector<Node>& nodes) {
  Node node{path, {}, {}, {}};
  for (const CLI::Option* opt : app.get_options()) {
    if (!opt->nonpositional() || opt->get_group().empty()) continue;
    std::vector<std::string> names;
    for (const auto& l : opt->get_lnames()) names.push_back("--" + l);
    for (const auto& s : opt->get_snames()) names.push_back("-" + s);
    for (const auto& n : names) {
      node.options.push_back({n, opt->get_description()});
      if (opt->get_expected_max() != 0) node.valued.push_back(n);
    }
  }
  const auto subcommands = app.get_subcommands(std::function<bool(const CLI::App*)>{});
  for (const CLI::App* sub : subcommands) {
    if (sub->get_name().empty() || sub->get_group().empty()) continue;
    node.children.push_back({sub->get_name(), sub->get_description()});
  }
  nodes.push_back(node);
  for (const CLI::App* sub : subcommands) {
    if (sub->get_name().empty() || sub->get_group().empty()) continue;
    walk(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), nodes);
  }
}

// A word in single quotes, for both shells.
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string names(const std::vector<Entry>& entries) {
  std::string out;
  for (const auto& e : entries) out += (out.empty() ? "" : " ") + e.name;
  return out;
}

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

void write_bash(const std::vector<Node>& nodes, const std::string& version) {
  std::cout << "# bash completion for hmc, written by `hmc completion bash` (" << version << ").\n"
            << "# _hmc_node PATH sets the subcommands, options and valued options of a command path.\n"
            << "_hmc_node() {\n  case \"$1\" in\n";
  for (const auto& n : nodes) {
    std::cout << "    " << quoted(n.path) << ")\n"
              << "      _hmc_children=" << quoted(names(n.children)) << "\n"
              << "      _hmc_options=" << quoted(names(n.options)) << "\n"
              << "      _hmc_valued=" << quoted(joined(n.valued)) << " ;;\n";
  }
  std::cout << "    *) _hmc_children='' _hmc_options='' _hmc_valued='' ;;\n  esac\n}\n\n"
            << R"(_hmc() {
  local cur="${COMP_WORDS[COMP_CWORD]}" path='' word i
  local _hmc_children _hmc_options _hmc_valued root_options root_valued
  _hmc_node ''
  root_options=$_hmc_options root_valued=$_hmc_valued
  COMPREPLY=()
  for ((i = 1; i < COMP_CWORD; i++)); do
    word="${COMP_WORDS[i]}"
    _hmc_node "$path"
    if [[ " $_hmc_children " == *" $word "* ]]; then
      path="${path:+$path }$word"
    elif [[ " $_hmc_valued $root_valued " == *" $word "* ]]; then
      ((i++))
    fi
  done
  ((i > COMP_CWORD)) && return 0  # the cursor is on an option's value: file names
  _hmc_node "$path"
  if [[ $cur == -* ]]; then
    [[ -n $path ]] && _hmc_options+=" $root_options"
    mapfile -t COMPREPLY < <(compgen -W "$_hmc_options" -- "$cur")
  elif [[ -n $_hmc_children ]]; then
    mapfile -t COMPREPLY < <(compgen -W "$_hmc_children" -- "$cur")
  fi
  return 0
}
complete -o default -F _hmc hmc
)";
}

// zsh's _describe reads "name:description"; a colon inside the name is escaped.
std::string described(const Entry& e) {
  std::string name;
  for (char c : e.name) name += c == ':' ? std::string("\\:") : std::string(1, c);
  return quoted(name + ":" + e.description);
}

void write_zsh(const std::vector<Node>& nodes, const std::string& version) {
  std::cout << "#compdef hmc\n"
            << "# zsh completion for hmc, written by `hmc completion zsh` (" << version << ").\n"
            << "# _hmc_node PATH sets the subcommands, options and valued options of a command path.\n"
            << "_hmc_node() {\n  children=() child_names=() options=() valued=()\n  case \"$1\" in\n";
  for (const auto& n : nodes) {
    std::cout << "    " << quoted(n.path) << ")\n      children=(";
    for (const auto& c : n.children) std::cout << " " << described(c);
    std::cout << " )\n      child_names=(" << names(n.children) << ")\n      options=(";
    for (const auto& o : n.options) std::cout << " " << described(o);
    std::cout << " )\n      valued=(" << joined(n.valued) << ") ;;\n";
  }
  std::cout << "  esac\n}\n\n"
            << R"(_hmc() {
  local cmdpath='' word i
  local -a children child_names options valued root_options root_valued
  _hmc_node ''
  root_options=("${options[@]}") root_valued=("${valued[@]}")
  for ((i = 2; i < CURRENT; i++)); do
    word=${words[i]}
    _hmc_node "$cmdpath"
    if (( ${child_names[(Ie)$word]} )); then
      cmdpath=${cmdpath:+$cmdpath }$word
    elif (( ${valued[(Ie)$word]} || ${root_valued[(Ie)$word]} )); then
      (( i++ ))
    fi
  done
  if (( i > CURRENT )); then _files; return; fi  # the cursor is on an option's value
  _hmc_node "$cmdpath"
  if [[ $PREFIX == -* ]]; then
    [[ -n $cmdpath ]] && options+=("${root_options[@]}")
    _describe -t options option options
  elif (( ${#children} )); then
    _describe -t commands command children
  else
    _files
  fi
}

_hmc "$@"
)";
}

}  // namespace

void add_completion_command(CLI::App& app, int& exit_code) {
  auto shell = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "completion", "Print a shell completion script: source it, or install it where the shell reads completions");
  cmd->add_option("SHELL", *shell, "bash or zsh")->required()->check(CLI::IsMember({"bash", "zsh"}));
  cmd->footer(
      "Examples:\n"
      "  source <(hmc completion bash)                         # this shell only\n"
      "  hmc completion bash > ~/.local/share/bash-completion/completions/hmc\n"
      "  hmc completion zsh > ~/.zfunc/_hmc                    # a directory on $fpath\n"
      "Installed hmc packages put both scripts where the shells look already.");
  cmd->callback([&app, shell, &exit_code] {
    std::vector<Node> nodes;
    walk(app, "", nodes);
    const std::string version = std::string("hmc ") + HMC_VERSION;
    if (*shell == "bash") {
      write_bash(nodes, version);
    } else {
      write_zsh(nodes, version);
    }
    exit_code = kExitOk;
  });
}

}  // namespace hmc::cli
