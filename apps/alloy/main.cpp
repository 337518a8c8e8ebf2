#include <iostream>

#include "apps/alloy/commands.hpp"

int main(int argc, char** argv) { return alloy::app::run_cli(argc, argv, std::cout, std::cerr); }
