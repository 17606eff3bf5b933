// `cairn people bench` verb (kept apart from the classifier verbs).
#pragma once
int runBenchVerb(int argc, char** argv);
