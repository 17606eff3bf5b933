// Verbs of `cairn slam` implemented outside cairn_slam.cpp (one function per verb; args exclude the verb).
// Each returns the process exit code: 0 ok, 1 failure of the work itself, 2 bad arguments or bad input.
#pragma once

#include <string>
#include <vector>

int slamRunVerb(const std::vector<std::string>& args);   // tools/slam_run.cpp
int slamEvalVerb(const std::vector<std::string>& args);  // tools/slam_run.cpp
int trainVerifierVerb(const std::vector<std::string>& args);  // tools/train_verifier.cpp: cairn slam train-verifier
int evalVerifierVerb(const std::vector<std::string>& args);   // tools/train_verifier.cpp: cairn slam eval-verifier
/// `cairn slam params [--markdown]`: the SLAM parameter table (config keys = component parameters)
int slamParamsVerb(const std::vector<std::string>& args);
