// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_parameters: prints the parameter documentation generated from the tables in the code.
//   oefmt_parameters --markdown > doc/parameters.md
//   oefmt_parameters --yaml > config/default.yaml
#include <cstdio>
#include <string>

#include "parameter_doc.h"

int main(int argc, char** argv) {
  const std::string what = argc == 2 ? argv[1] : "";
  if (what == "--markdown") {
    std::fputs(oefmt::parametersMarkdown().c_str(), stdout);
  } else if (what == "--yaml") {
    std::fputs(oefmt::defaultConfigYaml().c_str(), stdout);
  } else {
    std::fprintf(stderr,
                 "usage: oefmt_parameters --markdown   doc/parameters.md (every parameter, generated)\n"
                 "       oefmt_parameters --yaml       config/default.yaml (every default)\n");
    return what == "--help" || what == "-h" ? 0 : 2;
  }
  return 0;
}
