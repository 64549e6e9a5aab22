// The robot tests' main: gtest's, ended without static destructors (std::quick_exit).
// ign-transport 11's discovery threads outlive main and may dispatch a message into its shared
// node while the static destructors tear it down (a segfault after every test passed, seen under
// load; gz-sim #1317).
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
  // std::quick_exit runs what the tests registered with std::at_quick_exit (stopping a roscore of
  // their own), and no static destructor.
  std::quick_exit(result);
}
