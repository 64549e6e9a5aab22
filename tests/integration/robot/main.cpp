// The robot tests' main: gtest's, ended without static destructors. ign-transport 11's discovery
// threads outlive main and may dispatch a message into its shared node while the static
// destructors tear it down (a segfault after every test passed, seen under load; gz-sim #1317).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(result);
}
