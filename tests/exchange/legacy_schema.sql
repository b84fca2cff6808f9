-- The table layout of an original FTT database (fkie/field_test_tool), as the
-- feature inventory describes it, for the legacy-import tests.  Written for
-- these tests: only what the importer reads, no topology, no debug view.
CREATE EXTENSION IF NOT EXISTS postgis;

CREATE TABLE weather (
    id serial PRIMARY KEY, key varchar(512), short_description varchar(512),
    long_description text, icon_filename varchar(256));
CREATE TABLE ito_reason (
    id serial PRIMARY KEY, key varchar(512), short_description varchar(512),
    long_description text, has_duration char(1), color varchar(32));
CREATE TABLE segment_type (
    id serial PRIMARY KEY, key varchar(512), short_description varchar(512),
    long_description text, color varchar(32));

CREATE TABLE personnel (id serial PRIMARY KEY, name varchar(512), institution varchar(512));
CREATE TABLE performer (id serial PRIMARY KEY, institution varchar(512));
CREATE TABLE vehicle (
    id serial PRIMARY KEY, key varchar(512), short_description varchar(512),
    long_description text, institution varchar(512), configuration text);
CREATE TABLE pose_source (
    id serial PRIMARY KEY, key varchar(512), short_description varchar(512),
    long_description text);

CREATE TABLE test_event (
    id serial PRIMARY KEY, starttime_secs double precision, endtime_secs double precision,
    location varchar(512), version varchar(512), time_zone varchar(512), note text);
CREATE TABLE shift (
    id serial PRIMARY KEY,
    test_event_id integer REFERENCES test_event(id) ON DELETE CASCADE,
    starttime_secs double precision, endtime_secs double precision,
    test_administrator_id integer REFERENCES personnel(id),
    test_director_id integer REFERENCES personnel(id),
    safety_officer_id integer REFERENCES personnel(id),
    robot_operator_id integer REFERENCES personnel(id),
    performer_id integer REFERENCES performer(id),
    test_intent varchar(512), workspace varchar(512),
    vehicle_id integer REFERENCES vehicle(id), note text, number integer);
CREATE TABLE leg (
    id serial PRIMARY KEY,
    shift_id integer REFERENCES shift(id) ON DELETE CASCADE,
    number integer, starttime_secs double precision, endtime_secs double precision,
    weather_id integer REFERENCES weather(id),
    default_pose_source_id integer REFERENCES pose_source(id),
    bag_file varchar(512), note text);
CREATE TABLE segment (
    id serial PRIMARY KEY,
    leg_id integer REFERENCES leg(id) ON DELETE CASCADE,
    parent_id integer REFERENCES segment(id) ON DELETE CASCADE,
    ito_reason_id integer REFERENCES ito_reason(id),
    segment_type_id integer REFERENCES segment_type(id),
    starttime_secs double precision, endtime_secs double precision,
    obstacle varchar(512), lighting varchar(512), slope varchar(512),
    distance double precision,
    start_position geometry(Point, 4326),
    local_start_position geometry(Point),
    orig_starttime_secs double precision);
CREATE TABLE pose (
    id bigserial PRIMARY KEY, position geometry(Point, 4326), secs double precision,
    segment_id integer REFERENCES segment(id) ON DELETE CASCADE,
    pose_source_id integer REFERENCES pose_source(id), orig_secs double precision);
CREATE TABLE local_pose (
    id serial PRIMARY KEY,
    segment_id integer NOT NULL REFERENCES segment(id) ON DELETE CASCADE,
    secs double precision, frame_id varchar(512), position geometry(Point),
    orig_secs double precision);
CREATE TABLE map_image (
    id serial PRIMARY KEY,
    shift_id integer NOT NULL UNIQUE REFERENCES shift(id) ON DELETE CASCADE,
    secs double precision, frame_id varchar(512), width integer, height integer,
    resolution double precision, origin geometry(Point), image_data bytea,
    orig_secs double precision);
CREATE TABLE image (
    id serial PRIMARY KEY,
    segment_id integer REFERENCES segment(id) ON DELETE CASCADE,
    image_filename varchar(512), image_data bytea, description varchar(512),
    secs double precision, orig_secs double precision);
CREATE TABLE note (
    id serial PRIMARY KEY,
    segment_id integer REFERENCES segment(id) ON DELETE CASCADE,
    note text, secs double precision,
    personnel_id integer REFERENCES personnel(id));

-- A few catalogue rows with the original's explicit ids.
INSERT INTO segment_type VALUES
    (1, 'ito', 'ITO', 'Inhabited take over.', '255,0,0'),
    (2, 'auto', 'AUTO', 'Autonomous.', '0,255,0');
INSERT INTO ito_reason VALUES
    (1, 'safety', 'Safety', 'Stopped by an inhabitant.', 'F', '255,0,0'),
    (10, 'other', 'Other', 'Other reasons.', 'F', ' 180,180,180'),
    (11, 'unassigned', 'Unassigned', 'Unassigned.', 'F', '80,80,80'),
    (13, 'battery', 'Battery', 'Battery swap (a reason only this site had).', 'T', '9,9,9');
INSERT INTO weather VALUES
    (1, 'sunny', 'sunny', 'Mainly sunny.', 'sun79'),
    (2, 'cloudy', 'cloudy', 'Mainly cloudy.', 'cloudy19');
