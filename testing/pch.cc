// Compiles testing/pch.h once; every test and benchmark reuses it (testing/CMakeLists.txt).
