#pragma once

// `cairn people mask-bench ...` (built when the SLAM front end and the simulator are part of the build).
int runMaskBenchVerb(int argc, char** argv);
