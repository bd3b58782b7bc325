// specbake: the command-line entry point (cli/app.h).
#include "cli/app.h"

int main(int argc, char** argv) { return specbake::cli::run_cli(argc, argv); }
